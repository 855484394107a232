"""The course's triangle test's per-triangle records: each triangle's plane and the inverse of
[e1 e2 N] that gives its barycentric coordinates, as the course computes them."""
from __future__ import annotations

import numpy as np

from .matrices import inverse3


def course_records(v: np.ndarray) -> np.ndarray:
    """(T, 3, 3) float32 vertices -> the triangle test's records, (T, 16) float32.

    One record of 16 floats per triangle, read with two 8-wide packet gathers: (v0, offset, N,
    M20) (M00, M01, M02, M21, M10, M11, M12, M22) with M = [e1 e2 N]^-1 as the course inverts
    it (rows 0 and 1 give u and v, row 2 w). The file order, instance and mesh space are
    arrays of their own, read only where needed (a tie, an untransformed ray, a ray the octree
    takes): the third packet gather a test had (~40 of its ~225 cycles by llvm-mca) is gone,
    for no time difference measurable in renders."""
    npf = np.float32
    v0, e1, e2 = v[:, 0], v[:, 1] - v[:, 0], v[:, 2] - v[:, 0]
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        c = np.cross(e1, e2).astype(npf)
        n = c / np.sqrt((c[:, 0] * c[:, 0] + c[:, 1] * c[:, 1]) + c[:, 2] * c[:, 2])[:, None]
        offset = ((v0[:, 0] * n[:, 0] + v0[:, 1] * n[:, 1]) + v0[:, 2] * n[:, 2])
        inv = inverse3(np.stack([e1, e2, n], axis=-1))
    record = np.zeros((len(v), 16), np.float32)
    record[:, 0:3], record[:, 3], record[:, 4:7] = v0, offset, n
    record[:, 8:11], record[:, 12:15] = inv[:, 0], inv[:, 1]
    record[:, 7], record[:, 11], record[:, 15] = inv[:, 2, 0], inv[:, 2, 1], inv[:, 2, 2]
    return record
