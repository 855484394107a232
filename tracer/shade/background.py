"""What a ray that hits nothing sees: the background color or a cube-map texel (spec §7)."""
from __future__ import annotations

import numpy as np

from ..kernel.backend import import_drjit
from ..kernel.uniforms import uniform
from ..kernel.vecmath import Types, normalize
from ..scene.model import Background as BackgroundSpec

# Face order of the packed texel array.
RIGHT, LEFT, UP, DOWN, FRONT, BACK = range(6)
_FACE_FILES = {RIGHT: "right", LEFT: "left", UP: "up", DOWN: "down", FRONT: "front", BACK: "back"}


class Background:
    """The course's background lookup (robust.py's subclass: robust mode's)."""

    def __init__(self, spec: BackgroundSpec, types: Types) -> None:
        self.T = types
        self.dr = import_drjit()
        self.color = uniform(types, spec.color)
        self.cube = spec.cube_map
        if self.cube is not None:
            faces = [self.cube.rgb8[_FACE_FILES[k]] for k in range(6)]
            offsets = np.cumsum([0] + [f.shape[0] * f.shape[1] for f in faces])[:6]
            self.texels = self._texel_values(np.concatenate([f.reshape(-1) for f in faces]))
            self.offset = types.UInt32(offsets.astype(np.uint32))
            self.width = types.UInt32(np.array([f.shape[1] for f in faces], np.uint32))
            self.height = types.UInt32(np.array([f.shape[0] for f in faces], np.uint32))
            self.widthf = types.Float(np.array([f.shape[1] for f in faces], types.np_float))
            self.heightf = types.Float(np.array([f.shape[0] for f in faces], types.np_float))

    def _texel_values(self, rgb8: np.ndarray):
        """The packed bytes as texel values, float32(byte) / 255.0f (spec §7), converted on
        the device: a 6x1024^2 map goes up as 19 MB of bytes instead of 75 MB of floats,
        converted on the host in one thread (together 0.26 s of a 0.65 s render process).
        The values come from a 256-entry table divided on the host: Dr.Jit turns a division
        by a literal into a multiplication, which rounds some quotients differently."""
        T, dr = self.T, self.dr
        table = np.divide(np.arange(256, dtype=np.float32), np.float32(255.0), dtype=np.float32)
        texels = dr.gather(T.Float, T.Float(table.astype(T.np_float)),
                           T.UInt32(T.ns.UInt8(rgb8)))
        dr.eval(texels)  # once, not inside every kernel that reads the map
        return texels

    def lookup(self, d):
        if self.cube is None:
            return self.color
        return self._cube_lookup(d)

    def _cube_lookup(self, d):
        T, dr = self.T, self.dr
        n = normalize(d)
        ax, ay, az = dr.abs(n.x), dr.abs(n.y), dr.abs(n.z)
        use_x = (ax >= ay) & (ax >= az)
        use_y = ~use_x & (ay >= az)
        use_z = ~use_x & ~use_y
        major = dr.select(use_x, n.x, dr.select(use_y, n.y, n.z))
        first = dr.select(use_x, n.z, n.x)
        second = dr.select(use_y, n.z, n.y)
        p = (first / major + 1.0) * 0.5
        q = (second / major + 1.0) * 0.5
        pos = major > 0.0
        u = dr.select((use_y & ~pos) | (use_z & pos), 1.0 - p, p)
        v = dr.select(~pos, 1.0 - q, q)
        face = dr.select(use_x, dr.select(pos, RIGHT, LEFT),
                         dr.select(use_y, dr.select(pos, UP, DOWN), dr.select(pos, FRONT, BACK)))
        face = T.UInt32(face)
        return self._black_where_undefined(self._bilinear(face, u, v), major, u, v)

    def _black_where_undefined(self, color, major, u, v):
        """The course's zero-major rule: a zero direction sees black."""
        return self.dr.select(major == 0.0, self.T.Array3f(0.0), color)

    def _bilinear(self, face, u, v):
        T, dr = self.T, self.dr
        w = dr.gather(T.UInt32, self.width, face)
        h = dr.gather(T.UInt32, self.height, face)
        x = u * dr.gather(T.Float, self.widthf, face)
        y = (1.0 - v) * dr.gather(T.Float, self.heightf, face)
        # int() truncates; NaN/out-of-range give garbage indices that the clamp keeps in the
        # face, and the NaN weights then make the texel NaN as in the course's arithmetic.
        xi, yi = T.Int32(x), T.Int32(y)
        a = x - T.Float(xi)
        b = y - T.Float(yi)
        wmax, hmax = T.Int32(w) - 1, T.Int32(h) - 1
        i0, i1 = dr.clip(xi, 0, wmax), dr.clip(xi + 1, 0, wmax)
        j0, j1 = dr.clip(yi, 0, hmax), dr.clip(yi + 1, 0, hmax)
        base = dr.gather(T.UInt32, self.offset, face)

        def texel(i, j):
            idx = (base + T.UInt32(j) * w + T.UInt32(i)) * 3
            return T.Array3f(dr.gather(T.Float, self.texels, idx),
                             dr.gather(T.Float, self.texels, idx + 1),
                             dr.gather(T.Float, self.texels, idx + 2))

        w00 = (1.0 - a) * (1.0 - b)
        w10 = a * (1.0 - b)
        w01 = (1.0 - a) * b
        w11 = a * b
        return (((texel(i0, j0) * w00 + texel(i1, j0) * w10) + texel(i0, j1) * w01)
                + texel(i1, j1) * w11)
