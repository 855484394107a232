"""Plain data describing a parsed course scene; shared by the tracer and the Mitsuba translator.

Vectors are tuples of Python floats holding float32 values exactly (the course renderer parses
into float32). Matrices are 4x4 float32 numpy arrays mapping child space to parent space.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path
from typing import Iterator, Union

import numpy as np

Vec3 = tuple[float, float, float]


@dataclass(frozen=True)
class Camera:
    center: Vec3
    direction: Vec3
    up: Vec3
    angle_deg: float
    line: int = 0


@dataclass(frozen=True)
class DirectionalLight:
    direction: Vec3  # normalized at parse time; the direction light travels
    color: Vec3
    line: int = 0


@dataclass(frozen=True)
class PointLight:
    position: Vec3 = (0.0, 0.0, 0.0)
    color: Vec3 = (0.0, 0.0, 0.0)
    falloff: float = 0.0
    line: int = 0


Light = Union[DirectionalLight, PointLight]


@dataclass(frozen=True)
class Material:
    diffuse: Vec3 = (1.0, 1.0, 1.0)
    specular: Vec3 = (0.0, 0.0, 0.0)
    shininess: float = 0.0
    line: int = 0


@dataclass(frozen=True)
class CubeMap:
    """Six faces, each the PNG's (H, W, 3) uint8 texels with row 0 = its top row."""

    folder: Path
    rgb8: dict[str, np.ndarray]

    FACE_NAMES = ("left", "right", "up", "down", "front", "back")

    @cached_property
    def faces(self) -> dict[str, np.ndarray]:
        """The texel values of spec §7, float32(byte) / 255.0f (read-only: shared)."""
        faces = {name: np.divide(b, np.float32(255.0), dtype=np.float32)
                 for name, b in self.rgb8.items()}
        for values in faces.values():
            values.setflags(write=False)
        return faces


@dataclass(frozen=True)
class Background:
    color: Vec3 = (0.5, 0.5, 0.5)
    ambient: Vec3 = (0.0, 0.0, 0.0)
    cube_map: CubeMap | None = None


@dataclass(frozen=True)
class Sphere:
    center: Vec3
    radius: float
    material: int
    line: int = 0


@dataclass(frozen=True)
class Plane:
    normal: Vec3  # as written, not normalized
    offset: float
    material: int
    line: int = 0


@dataclass(frozen=True)
class Triangle:
    v0: Vec3
    v1: Vec3
    v2: Vec3
    material: int
    line: int = 0


@dataclass(frozen=True, eq=False)
class Mesh:
    """A TriangleMesh: vertices (V,3) float32, faces (F,3) int64 0-based, normals (V,3) float32
    recomputed by the course's averaging rule."""

    path: Path
    vertices: np.ndarray
    faces: np.ndarray
    normals: np.ndarray
    material: int
    line: int = 0


@dataclass(frozen=True, eq=False)
class Transform:
    matrix: np.ndarray  # 4x4 float32, child space -> parent space
    child: "SceneObject"
    line: int = 0


@dataclass(frozen=True)
class Group:
    objects: tuple["SceneObject", ...] = ()
    line: int = 0


SceneObject = Union[Group, Sphere, Plane, Triangle, Mesh, Transform]


def primitives(obj: SceneObject) -> Iterator[tuple[Sphere | Plane | Triangle | Mesh, int]]:
    """Every primitive under obj with the number of Transforms above it (in no set order)."""
    stack: list[tuple[SceneObject, int]] = [(obj, 0)]
    while stack:
        o, depth = stack.pop()
        if isinstance(o, Group):
            stack.extend((child, depth) for child in o.objects)
        elif isinstance(o, Transform):
            stack.append((o.child, depth + 1))
        else:
            yield o, depth
Primitive = Union[Sphere, Plane, Triangle, Mesh]


@dataclass(frozen=True)
class Scene:
    path: Path
    camera: Camera
    lights: tuple[Light, ...] = ()
    background: Background = field(default_factory=Background)
    materials: tuple[Material, ...] = ()
    root: Group = field(default_factory=Group)


REFLECTIVE_KS = 0.1  # mirror recursion happens where |ks| > 0.1 (spec §6)


def reflective_mask(materials) -> np.ndarray:
    """Per material: does it recurse, |ks| > 0.1 with |ks| the float32 Euclidean length."""
    ks = np.array([m.specular for m in materials], np.float32).reshape(-1, 3)
    length = np.sqrt((ks[:, 0] * ks[:, 0] + ks[:, 1] * ks[:, 1]) + ks[:, 2] * ks[:, 2])
    return length > np.float32(REFLECTIVE_KS)
