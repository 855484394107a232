"""Pass/fail thresholds of the comparison, each with the reason for its value."""
from __future__ import annotations

# Wang et al. SSIM of the shown (clipped) float images, data_range 1. Course mode and the
# Mitsuba reference compute the same model with different intersection code: differences are
# rounding at silhouettes and shadow/mirror boundaries, a few pixels per image; 0.995 allows
# those and fails on any systematic error (a wrong light, normal or offset changes SSIM by
# more than 0.01 on our scenes).
SSIM_MIN = 0.995

# Share of 8-bit pixels whose channels all lie within 1 level of the other renderer's. Rounding
# flips single bytes; 0.5% leaves room for boundary pixels (silhouettes, shadow edges, the
# finite rectangle standing in for an infinite plane near the horizon).
WITHIN_ONE_LEVEL_MIN = 0.995

# Jittered cases: both renderers' 16-sample images are compared with a converged render of
# the same renderer (CONVERGED_SAMPLES samples); their RMSEs must be of the same size, i.e.
# within this factor of each other. The noise sits in the few edge pixels of a small image, so
# one RMSE estimate varies by 20-30% between seeds (axes/jitter depth at 48 px: 0.0064 and
# 0.0096 for the tracer with seeds 0 and 5, 0.0109 and 0.0103 for Mitsuba); a factor of 2 is
# about three standard deviations of that spread, while a wrong sample distribution (e.g. no
# jitter, or jitter over two pixels) changes the error by far more.
JITTER_RMSE_RATIO_MAX = 2.0
# ...and the two converged renders must agree, with SSIM alone (no 8-bit level test): at 256
# samples the noise left is about 1/16 of one sample's, which on sub-pixel detail is still a
# few levels (jitter_filter/jitter at 48 px: SSIM 0.992 between the two converged renders).
CONVERGED_SAMPLES = 256
CONVERGED_SSIM_MIN = 0.99
# Below this RMSE both jittered images are essentially converged (flat scenes) and the ratio
# says nothing.
JITTER_RMSE_FLOOR = 1e-3

# Converged depth images are not compared across renderers: a jittered depth pixel is black as
# soon as one of its samples misses (spec §9), so with 256 samples each silhouette pixel with a
# small missed share is black or not by chance, differently in each renderer. The 16-sample
# RMSE ratio above still applies to depth.
JUDGE_CONVERGED_DEPTH = False
