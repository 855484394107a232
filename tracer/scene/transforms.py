"""The 4x4 float32 matrices of the course's Transform ops (spec §2, Transform ops)."""
from __future__ import annotations

import math

import numpy as np

F32 = np.float32


def _radians(deg: float) -> np.float32:
    # The course converts degrees in double and stores the angle as float.
    return F32(math.pi * deg / 180.0)


def _cos_sin(deg: float) -> tuple[np.float32, np.float32]:
    # The course takes cos and sin of the float angle in double and rounds them to float
    # (numpy's float32 cos and sin differ from that in the last bit for some angles).
    a = float(_radians(deg))
    if not math.isfinite(a):  # C's cos and sin of ±inf or NaN are NaN (Python's raise)
        return F32("nan"), F32("nan")
    return F32(math.cos(a)), F32(math.sin(a))


def translate(x: float, y: float, z: float) -> np.ndarray:
    m = np.eye(4, dtype=F32)
    m[:3, 3] = (x, y, z)
    return m


def scale(x: float, y: float, z: float) -> np.ndarray:
    return np.diag(np.array([x, y, z, 1.0], dtype=F32))


def _rotation(r3: np.ndarray) -> np.ndarray:
    m = np.eye(4, dtype=F32)
    m[:3, :3] = r3
    return m


def rotate_axis(axis: int, deg: float) -> np.ndarray:
    """Right-handed rotation about x (0), y (1) or z (2)."""
    c, s = _cos_sin(deg)
    if axis == 0:
        r = [[1, 0, 0], [0, c, -s], [0, s, c]]
    elif axis == 1:
        r = [[c, 0, s], [0, 1, 0], [-s, 0, c]]
    else:
        r = [[c, -s, 0], [s, c, 0], [0, 0, 1]]
    return _rotation(np.array(r, dtype=F32))


def rotate(ax: float, ay: float, az: float, deg: float) -> np.ndarray:
    """Rotation by deg about normalize(axis) (Rodrigues' formula)."""
    v = np.array([ax, ay, az], dtype=F32)
    with np.errstate(invalid="ignore", divide="ignore"):
        n = v / np.sqrt(np.dot(v, v))
    c, s = _cos_sin(deg)
    x, y, z = n
    one_c = F32(1) - c
    r = np.array(
        [
            [c + x * x * one_c, x * y * one_c - z * s, x * z * one_c + y * s],
            [y * x * one_c + z * s, c + y * y * one_c, y * z * one_c - x * s],
            [z * x * one_c - y * s, z * y * one_c + x * s, c + z * z * one_c],
        ],
        dtype=F32,
    )
    return _rotation(r)


def from_columns(values: list[float]) -> np.ndarray:
    """Matrix4f: 16 numbers, the first four are column 0."""
    return np.array(values, dtype=F32).reshape(4, 4).T.copy()


def product(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """a · b of 4x4 float32 matrices as the course's matrix class computes it: each entry's four
    products summed left to right, every step rounded to float32 (numpy's matmul may hand the
    product to a BLAS whose fused multiply-adds round once, a unit off in rotated scenes)."""
    a, b = np.asarray(a, F32), np.asarray(b, F32)
    with np.errstate(all="ignore"):
        out = a[:, 0:1] * b[0:1, :]
        for k in range(1, 4):
            out = out + a[:, k:k + 1] * b[k:k + 1, :]
    return out.astype(F32)
