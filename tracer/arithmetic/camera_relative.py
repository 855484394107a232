"""Robust mode: the scene moved so that the camera sits at the origin ("camera-relative").

Float32 spacing grows with magnitude: at 1e5 it is 0.008, at 1e7 it is 1, so hit points,
shading vectors and ray offsets computed in absolute coordinates far from the origin are noise
(acne, light leaks, wrong normals) even where the geometry itself is close to the camera.
Moving everything by -camera.center, in float64 and then rounded, keeps the numbers that the
kernel works with small. The geometry stays the parsed float32 geometry: differences of nearby
float32 values are exact (Sterbenz), so nothing near the camera moves. Depth is unaffected
(t is measured from the camera either way).
"""
from __future__ import annotations

from dataclasses import replace
from typing import overload

import numpy as np

from ..scene.model import (
    Camera,
    Group,
    Mesh,
    Plane,
    PointLight,
    Scene,
    SceneObject,
    Sphere,
    Transform,
    Triangle,
    Vec3,
)


def _sub(v: Vec3, c: np.ndarray) -> Vec3:
    r = (np.array(v, np.float64) - c).astype(np.float32)
    return (float(r[0]), float(r[1]), float(r[2]))


@overload
def _move(obj: Group, c: np.ndarray) -> Group: ...
@overload
def _move(obj: SceneObject, c: np.ndarray) -> SceneObject: ...


def _move(obj: SceneObject, c: np.ndarray) -> SceneObject:
    if isinstance(obj, Group):
        return replace(obj, objects=tuple(_move(o, c) for o in obj.objects))
    if isinstance(obj, Transform):
        # world' = T(-c)·M·p composed in float64, so that the inverse's translation is small;
        # what lies inside the transform keeps its own coordinates
        return replace(obj, matrix=_translate_rows(obj.matrix.astype(np.float64), c))
    if isinstance(obj, Sphere):
        return replace(obj, center=_sub(obj.center, c))
    if isinstance(obj, Plane):
        n = np.array(obj.normal, np.float64)
        return replace(obj, offset=float(np.float32(obj.offset - n @ c)))
    if isinstance(obj, Triangle):
        return replace(obj, v0=_sub(obj.v0, c), v1=_sub(obj.v1, c), v2=_sub(obj.v2, c))
    if isinstance(obj, Mesh):
        v = (obj.vertices.astype(np.float64) - c).astype(np.float32)
        return Mesh(obj.path, v, obj.faces, obj.normals, obj.material, obj.line)
    raise TypeError(type(obj))


def _translate_rows(m: np.ndarray, c: np.ndarray) -> np.ndarray:
    """T(-c)·M in float64, rounded to float32."""
    t = np.eye(4)
    t[:3, 3] = -c
    return (t @ m).astype(np.float32)


def camera_relative(scene: Scene) -> Scene:
    c = np.array(scene.camera.center, np.float64)
    if not np.isfinite(c).all() or not c.any():
        return scene
    with np.errstate(all="ignore"):  # inf/NaN scene values stay what they are
        lights = tuple(replace(li, position=_sub(li.position, c))
                       if isinstance(li, PointLight) else li for li in scene.lights)
        root = _move(scene.root, c)
    camera = Camera((0.0, 0.0, 0.0), scene.camera.direction, scene.camera.up,
                    scene.camera.angle_deg, scene.camera.line)
    return replace(scene, camera=camera, lights=lights, root=root)

