"""Shader.powf: the branch that packets skip (x = ±0, e > 0) returns what the double
evaluation gives there, so images cannot change with how lanes are grouped."""
from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from raycheck.tracer.kernel.backend import import_drjit
from raycheck.tracer.kernel.vecmath import make_types
from raycheck.tracer.shade.shading import Shader


def _powf(x: np.ndarray, e: np.ndarray) -> np.ndarray:
    T = make_types()
    shader = SimpleNamespace(dr=import_drjit(), T=T)
    return Shader.powf(shader, T.Float(x.astype(np.float32)), T.Float(e.astype(np.float32))).numpy()


def test_zero_base_gives_the_double_evaluations_values():
    e = np.array([1e-30, 1e-7, 0.5, 1, 30, 1e4, 1e38, np.inf, 0, -0.0, -1, -np.inf, np.nan])
    for zero in (0.0, -0.0):
        got = _powf(np.full(len(e), zero), e)
        # log2(±0) = -inf: times e > 0 rounds to 0; e < 0 gives inf; e = 0 gives 1; NaN stays
        want = np.array([0] * 8 + [1, 1, np.inf, np.inf, np.nan], np.float32)
        assert np.array_equal(got, want, equal_nan=True)


def test_lanes_that_skip_do_not_change_their_neighbours():
    # one packet of 16 lanes mixing zero and nonzero bases, and the same lanes alone
    rng = np.random.default_rng(3)
    x = rng.uniform(0, 1, 64).astype(np.float32)
    x[::3] = 0.0
    e = np.float32(rng.uniform(0.5, 200, 64))
    mixed = _powf(x, e)
    # the double evaluation on every lane, without the branch
    dr, T = import_drjit(), make_types()
    y = dr.log2(T.Float64(x)) * T.Float64(e)
    want = T.Float(dr.select(y < -151.0, 0.0, dr.exp2(y))).numpy()
    assert np.array_equal(mixed, want)
    assert (mixed[::3] == 0).all()


def test_a_negative_base_is_powfs():
    # C's powf: an integer exponent keeps the sign of the base's odd powers; another is NaN
    x = np.array([-0.5, -0.5, -2.0, -0.5, -1.0, -1.0], np.float32)
    e = np.array([2.0, 3.0, 10.0, 0.5, 1e-3, 80.0], np.float32)
    want = np.array([0.25, -0.125, 1024.0, np.nan, np.nan, 1.0], np.float32)
    assert np.array_equal(_powf(x, e), want, equal_nan=True)
