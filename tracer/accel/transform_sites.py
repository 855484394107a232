"""Transform::intersect's sites (operators.py): the course's parts move a ray into a
Transform's space and its hit normal back out through these, which give the course's
(spec §5); the mistaken parts (arithmetic/mistaken.py) override them."""
from __future__ import annotations

import numpy as np

from ..kernel.vecmath import div3, homogeneous, mat3_mul
from ..mistakes import hooks
from ..operators import CourseSites, Operator, Site, site_codes

# the sites that hand the object another ray
OBJECT_RAY = (Site.TRANSFORM_ORIGIN_DIVIDE, Site.TRANSFORM_ORIGIN_W, Site.TRANSFORM_DIRECTION_W,
              Site.TRANSFORM_RAY)
HOOKS = hooks(__name__, *site_codes(*OBJECT_RAY, Site.TRANSFORM_NORMAL_MATRIX))


class TransformSites(CourseSites):
    def object_ray(self, m, o, d):
        """The ray (o, d) through one level's inverse m (4x4 nested sequence of host floats or
        traced values, row-major), as vecmath.inverse_ray computes it."""
        p, w = homogeneous(m, o)
        # (o, 1 + change): the translation column and m[3][3] count 1 + change times
        p = self.site_added(Site.TRANSFORM_ORIGIN_W, p, type(o)(m[0][3], m[1][3], m[2][3]))
        w = self.site_added(Site.TRANSFORM_ORIGIN_W, w, m[3][3])
        origin = self.site_arithmetic(Site.TRANSFORM_ORIGIN_DIVIDE, div3(p, w), {
            Operator.PLUS: lambda: p + w, Operator.MINUS: lambda: p - w})
        direction = self.site_added(Site.TRANSFORM_DIRECTION_W, mat3_mul(m, d),
                                    type(d)(m[0][3], m[1][3], m[2][3]))
        return self.site_swapped(Site.TRANSFORM_RAY, origin, direction)

    def normal_options(self, inverse: np.ndarray, normal: np.ndarray) -> list[np.ndarray]:
        """The 3x3 matrices a hit normal may go through at one level (M^-1 `inverse`, the
        course's ((M3)^-1)^T `normal`), in TRANSFORM_NORMAL_MATRIX's order: the course's, and
        where a mistake there may be on, M3, M3^-1 and M3^T, and the inverse transposed of
        each other 3x3 block of M (a singular one's is NaN: the C++'s is not defined), as
        float32."""
        if not self.site_compiled(Site.TRANSFORM_NORMAL_MATRIX):
            return [normal]
        inverse3 = inverse[:3, :3].astype(np.float64)
        m3 = np.linalg.inv(inverse3)
        m = np.linalg.inv(inverse.astype(np.float64))
        blocks = []
        for i, j in ((0, 1), (1, 0), (1, 1)):
            block = m[i:i + 3, j:j + 3]
            singular = abs(np.linalg.det(block)) < 1e-12
            blocks.append(np.full((3, 3), np.nan) if singular else np.linalg.inv(block).T)
        return [normal, *(b.astype(np.float32) for b in (m3, inverse3, m3.T, *blocks))]

    def through_level(self, transformed: list):
        """The hit normal at one level, of those the normal_options give (`transformed`)."""
        return self.site_index(Site.TRANSFORM_NORMAL_MATRIX, transformed)
