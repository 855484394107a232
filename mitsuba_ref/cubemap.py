"""Cube-map background lookup of spec §7, written in Dr.Jit for the Mitsuba side.

Faces are the parser's float arrays (value = byte/255, row 0 = the PNG's top row). All six are
packed into one flat texel buffer so a lookup is one face choice plus four gathers.

    normalize d; the major axis is X if |x| >= |y| and |x| >= |z|, else Y if |y| >= |z|, else Z
    face   u                  v
    +X     (z/x + 1)/2        (y/x + 1)/2
    -X     (z/x + 1)/2        1 - (y/x + 1)/2
    +Y     (x/y + 1)/2        (z/y + 1)/2
    -Y     1 - (x/y + 1)/2    1 - (z/y + 1)/2
    +Z     1 - (x/z + 1)/2    (y/z + 1)/2
    -Z     (x/z + 1)/2        1 - (y/z + 1)/2
    X = u*W, Y = (1-v)*H, i = int(X), j = int(Y), a = X - i, b = Y - j, bilinear over
    (i,j) (i+1,j) (i,j+1) (i+1,j+1) with indices clamped to the face; a zero major component
    gives black.
"""
from __future__ import annotations

from pathlib import Path
from typing import cast

import drjit as dr
import mitsuba as mi
import numpy as np

from raycheck.tracer.scene.cubemap import load_cube_map
from raycheck.tracer.scene.model import CubeMap

# Face order of the packed buffer, indexed by major axis and sign: +X, -X, +Y, -Y, +Z, -Z.
FACE_ORDER = ("right", "left", "up", "down", "front", "back")


class CubeMapLookup:
    def __init__(self, cube_map: CubeMap) -> None:
        faces = [np.ascontiguousarray(cube_map.faces[name], dtype=np.float32)
                 for name in FACE_ORDER]
        sizes = [(f.shape[1], f.shape[0]) for f in faces]  # (W, H)
        offsets = np.cumsum([0] + [w * h for w, h in sizes[:-1]])
        self.folder = cube_map.folder
        self.texels = mi.Float(np.concatenate([f.reshape(-1) for f in faces]))
        self.offset = mi.UInt32(offsets.astype(np.uint32))
        self.width = mi.Int32(np.array([w for w, _ in sizes], dtype=np.int32))
        self.height = mi.Int32(np.array([h for _, h in sizes], dtype=np.int32))

    @classmethod
    def from_folder(cls, folder: Path) -> "CubeMapLookup":
        """For scenes loaded from XML: the folder holding left/right/up/down/front/back.png."""
        return cls(load_cube_map(Path(folder), Path(folder), 0))

    def lookup(self, d: mi.Vector3f, active: mi.Bool | bool = True) -> mi.Color3f:
        n = d / dr.sqrt((d.x * d.x + d.y * d.y) + d.z * d.z)
        x, y, z = n.x, n.y, n.z
        ax, ay, az = dr.abs(x), dr.abs(y), dr.abs(z)
        use_x = (ax >= ay) & (ax >= az)
        use_y = ~use_x & (ay >= az)
        major = dr.select(use_x, x, dr.select(use_y, y, z))
        positive = major > 0

        # a/b: the two ratios each face's (u, v) is built from
        a = dr.select(use_x, z / x, x / dr.select(use_y, y, z))
        b = dr.select(use_x, y / x, dr.select(use_y, z / y, y / z))
        s = (a + 1.0) / 2.0
        t = (b + 1.0) / 2.0
        u = dr.select(use_x | use_y, s, 1.0 - s)
        v = t
        # the mirrored ones: -X v, -Y u and v, +Z u (done above as 1 - s for Z), -Z v
        u = dr.select(use_y & ~positive, 1.0 - s, u)
        u = dr.select(~use_x & ~use_y & ~positive, s, u)
        v = dr.select(~positive, 1.0 - t, v)
        # an Int32 array (the stubs say int), hence its own name
        face_number = dr.select(use_x, 0, dr.select(use_y, 2, 4)) + dr.select(positive, 0, 1)
        face = mi.UInt32(face_number)

        width = dr.gather(mi.Int32, self.width, face, active)
        height = dr.gather(mi.Int32, self.height, face, active)
        base = dr.gather(mi.UInt32, self.offset, face, active)
        fx = u * mi.Float(width)
        fy = (1.0 - v) * mi.Float(height)
        i = mi.Int32(fx)  # C conversion: truncation toward zero
        j = mi.Int32(fy)
        # the stubs' Color3f takes only drjit.auto.ad.Float factors (their name for a variant's
        # Float, a class apart from their mi.Float)
        wa = cast("dr.auto.ad.Float", fx - mi.Float(i))
        wb = cast("dr.auto.ad.Float", fy - mi.Float(j))
        i0 = dr.clip(i, 0, width - 1)
        i1 = dr.clip(i + 1, 0, width - 1)
        j0 = dr.clip(j, 0, height - 1)
        j1 = dr.clip(j + 1, 0, height - 1)

        def texel(ii: mi.Int32, jj: mi.Int32) -> mi.Color3f:
            idx = (base + mi.UInt32(jj * width + ii)) * 3
            return mi.Color3f(dr.gather(mi.Float, self.texels, idx, active),
                              dr.gather(mi.Float, self.texels, idx + 1, active),
                              dr.gather(mi.Float, self.texels, idx + 2, active))

        color = (((1.0 - wa) * (1.0 - wb)) * texel(i0, j0)
                 + (wa * (1.0 - wb)) * texel(i1, j0)) \
            + ((1.0 - wa) * wb) * texel(i0, j1) + (wa * wb) * texel(i1, j1)
        return dr.select(active & (major != 0), color, 0.0)
