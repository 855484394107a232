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
# within this factor of each other (Monte Carlo noise of 16 samples varies by ~20% between
# seeds on our scenes).
JITTER_RMSE_RATIO_MAX = 1.6
# ...and the two converged renders must agree like deterministic ones do.
CONVERGED_SAMPLES = 256
# Below this RMSE both jittered images are essentially converged (flat scenes) and the ratio
# says nothing.
JITTER_RMSE_FLOOR = 1e-3
