"""Renderer bugs made by patching the reference tracer while it traces: each a context
manager under which raycheck.tracer renders with exactly that bug (corrupt.py's PATCHED
defects). Kernels are cached by their code, so a patched kernel never stands in for the
tracer's own.

specular_gated: the specular term only where N·L > 0 (the course adds it wherever R·L > 0);
ambient_per_light: ambient ⊙ kd added with every light's term, after its shadow test, instead
of once; half_vector: Blinn-Phong's (N·H)^shininess instead of (R·L)^shininess; no_offset: the
course's 0.01 offset of shadow and reflection rays dropped.
"""
from __future__ import annotations

from contextlib import contextmanager
from typing import Callable, ContextManager, Iterator


@contextmanager
def patched(owner, name: str, value) -> Iterator[None]:
    old = getattr(owner, name)
    setattr(owner, name, value)
    try:
        yield
    finally:
        setattr(owner, name, old)


def specular_gated() -> ContextManager:
    from raycheck.tracer.kernel.vecmath import dot
    from raycheck.tracer.shade.shading import Shader

    phong = Shader._phong

    def gated(self, n, to_light, rl, intensity, material, record=None, light=0):
        kd, ks, shininess = material
        ks = self.dr.select(dot(n, to_light) > 0.0, ks, 0.0)
        return phong(self, n, to_light, rl, intensity, (kd, ks, shininess), record, light)

    return patched(Shader, "_phong", gated)


@contextmanager
def ambient_per_light() -> Iterator[None]:
    from raycheck.tracer.shade.shading import Shader

    phong = Shader._phong

    def with_ambient(self, n, to_light, rl, intensity, material, record=None, light=0):
        ambient = self.T.Array3f(*self.scene.background.ambient) * material[0]
        return phong(self, n, to_light, rl, intensity, material, record, light) + ambient

    def no_ambient(self, mat):
        return self.dr.zeros(self.T.Array3f, self.dr.width(mat))

    with patched(Shader, "_phong", with_ambient), patched(Shader, "ambient", no_ambient):
        yield


def half_vector() -> ContextManager:
    from raycheck.tracer.kernel.vecmath import dot, normalize
    from raycheck.tracer.shade.shading import Shader

    def blinn(self, d, n, r, to_light):
        return dot(n, normalize(to_light - d))

    return patched(Shader, "highlight_cosine", blinn)


def no_offset() -> ContextManager:
    from raycheck.tracer.shade import shading

    return patched(shading, "SHADOW_OFFSET", 0.0)


PATCHED: dict[str, Callable[[], ContextManager]] = {
    "specular_gated": specular_gated,
    "ambient_per_light": ambient_per_light,
    "half_vector": half_vector,
    "no_offset": no_offset,
}
