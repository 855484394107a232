"""Matrix inverses in float32 as the course computes them (spec §5), on the host (numpy).

The course inverts by cofactors: each cofactor a 2x2 (3x3: a·d - b·c) or 3x3 determinant
(4x4), the determinant expanded along the first row, the inverse the adjugate times 1/det
(no singularity test: det 0 gives inf and NaN entries). Far from the origin (translations of
1e7) this differs from a float64 inverse rounded to float32 by whole units, which moves
transformed objects; course mode uses these.
"""
from __future__ import annotations

import numpy as np

F32 = np.float32


def _det2(a, b, c, d):
    return a * d - b * c


def _det3(m00, m01, m02, m10, m11, m12, m20, m21, m22):
    return ((m11 * m22 - m12 * m21) * m00 - (m10 * m22 - m12 * m20) * m01
            + (m10 * m21 - m11 * m20) * m02)


def inverse3(m: np.ndarray) -> np.ndarray:
    """(..., 3, 3) float32 matrices -> their course inverses."""
    m = np.asarray(m, F32)
    (m00, m01, m02), (m10, m11, m12), (m20, m21, m22) = (
        [m[..., i, j] for j in range(3)] for i in range(3))
    with np.errstate(all="ignore"):
        c = [[_det2(m11, m12, m21, m22), -_det2(m10, m12, m20, m22), _det2(m10, m11, m20, m21)],
             [-_det2(m01, m02, m21, m22), _det2(m00, m02, m20, m22), -_det2(m00, m01, m20, m21)],
             [_det2(m01, m02, m11, m12), -_det2(m00, m02, m10, m12), _det2(m00, m01, m10, m11)]]
        r = F32(1.0) / ((m00 * c[0][0] + m01 * c[0][1]) + m02 * c[0][2])
        return np.stack([np.stack([c[j][i] * r for j in range(3)], -1) for i in range(3)], -2)


def inverse4(m: np.ndarray) -> np.ndarray:
    """A 4x4 float32 matrix -> its course inverse."""
    e = np.asarray(m, F32)

    def at(i: int, j: int):
        return e[i % 4, j % 4]

    with np.errstate(all="ignore"):
        # cofactor (i, j): the 3x3 minor of rows i+1.., columns j+1.. (cyclic), signed
        c = [[(1 if (i + j) % 2 == 0 else -1)
              * _det3(*(at(i + 1 + a, j + 1 + b) for a in range(3) for b in range(3)))
              for j in range(4)] for i in range(4)]
        det = ((e[0, 0] * c[0][0] + e[0, 1] * c[0][1]) + e[0, 2] * c[0][2]) + e[0, 3] * c[0][3]
        r = F32(1.0) / det
        return np.array([[c[j][i] * r for j in range(4)] for i in range(4)], F32)
