"""Geometry bugs made by patching the reference tracer while it renders (corrupt.py's
GEOMETRY defects), context managers as in patched.py:

unnormalised_normals: a transformed object's world normal N·n is not renormalised (spheres and
planes in intersect.py, triangles and meshes in triangles.py): only objects under a transform
that scales change. one_material: the scene's first leaf object in file order is rendered with
the next material index (wrapping). pixel_centre: the primary ray through pixel x has
ndc = 2*(x+0.5)/w - 1 instead of the course's 2*x/(w-1) - 1. half_shift: primary rays through
x+0.5, y+0.5 with the course's ndc: the image moves by half a pixel. sphere_shrunk: every
sphere is intersected with 0.8 times its radius (no catalogue mistake: a Sphere::intersect bug
of the kind localisation finds).
"""
from __future__ import annotations

from contextlib import contextmanager
from dataclasses import replace
from typing import Callable, ContextManager, Iterator

from patched import patched


@contextmanager
def unnormalised_normals() -> Iterator[None]:
    from raycheck.tracer.accel.intersect import Intersector
    from raycheck.tracer.accel.triangles import TriangleSet

    spheres_planes = Intersector._world_normal

    def kept(v):
        return v

    def sphere_plane_normal(self, xf, n, unit=None):
        return spheres_planes(self, xf, n, kept)

    world_unit = TriangleSet.__dict__["world_unit"]  # the staticmethod itself, to restore
    with patched(Intersector, "_world_normal", sphere_plane_normal):
        TriangleSet.world_unit = staticmethod(kept)
        try:
            yield
        finally:
            TriangleSet.world_unit = world_unit


def first_leaf_material_changed(scene):
    """The scene with its first leaf object given the next material index."""
    from raycheck.tracer.scene.model import Group, Transform

    def change(obj):  # (the object with its first leaf changed, whether one was found)
        if isinstance(obj, Group):
            for i, child in enumerate(obj.objects):
                new, done = change(child)
                if done:
                    return replace(obj, objects=obj.objects[:i] + (new,)
                                   + obj.objects[i + 1:]), True
            return obj, False
        if isinstance(obj, Transform):
            new, done = change(obj.child)
            return replace(obj, child=new), done
        return replace(obj, material=(obj.material + 1) % len(scene.materials)), True

    return replace(scene, root=change(scene.root)[0])


def spheres_shrunk(scene):
    """The scene with every sphere's radius times 0.8."""
    from raycheck.tracer.scene.model import Group, Sphere, Transform

    def change(obj):
        if isinstance(obj, Group):
            return replace(obj, objects=tuple(change(child) for child in obj.objects))
        if isinstance(obj, Transform):
            return replace(obj, child=change(obj.child))
        return replace(obj, radius=0.8 * obj.radius) if isinstance(obj, Sphere) else obj

    return replace(scene, root=change(scene.root))


def sphere_shrunk() -> ContextManager:
    from raycheck.tracer import scene as scene_package

    load = scene_package.load_scene
    return patched(scene_package, "load_scene", lambda path, *a: spheres_shrunk(load(path, *a)))


def one_material() -> ContextManager:
    from raycheck.tracer import scene as scene_package

    load = scene_package.load_scene
    return patched(scene_package, "load_scene",
                   lambda path, *a: first_leaf_material_changed(load(path, *a)))


def pixel_centre() -> ContextManager:
    from raycheck.tracer.render import Renderer

    def centred(self, p, n, axis):
        return 2.0 * ((p + 0.5) / self._opaque(self.T.Float, float(n))) - 1.0

    return patched(Renderer, "_ndc", centred)


def half_shift() -> ContextManager:
    from raycheck.tracer.render import Renderer

    ndc = Renderer._ndc
    return patched(Renderer, "_ndc", lambda self, p, n, axis: ndc(self, p + 0.5, n, axis))


GEOMETRY: dict[str, Callable[[], ContextManager]] = {
    "unnormalised_normals": unnormalised_normals,
    "one_material": one_material,
    "sphere_shrunk": sphere_shrunk,
    "pixel_centre": pixel_centre,
    "half_shift": half_shift,
}
