"""Seeded random triangles around (0, 0, -4) for the tests that compare candidate lists with
the BVH (test_screen_tiles, test_shadow_grid): thin, mid-sized and large ones mixed."""
from __future__ import annotations

import numpy as np


def random_triangles(rng: np.random.Generator) -> list[np.ndarray]:
    """4 to 39 triangles, each (3, 3): a corner, and two more around it at a spread of 0.05,
    0.5 or 3."""
    corners = []
    for _ in range(int(rng.integers(4, 40))):
        p = rng.normal(0, 2, 3) + (0, 0, -4)
        corners.append(np.concatenate([[p], p + rng.normal(0, rng.choice([0.05, 0.5, 3]),
                                                           (2, 3))]))
    return corners


def triangle_lines(triangles: list[np.ndarray]) -> list[str]:
    """Each triangle as a course Triangle primitive."""
    return ["Triangle { vertex0 %f %f %f vertex1 %f %f %f vertex2 %f %f %f }"
            % tuple(tri.ravel()) for tri in triangles]
