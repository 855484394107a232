"""The scene tree flattened into what the kernel intersects (host side, numpy float32).

Spheres and planes keep their object space: rays go into it through the inverse transform, as in
the course renderer, so a non-uniformly scaled sphere stays an exact ellipsoid (spec §5).
Triangles are moved to world space once (the spec allows it: same image up to rounding), with
their vertex normals multiplied by M^-T but left unnormalized, so that interpolating and then
normalizing gives the course's normalize(M^-T · normalize(interpolated)).

Every primitive gets its file-order number: ties in t go to the earlier one, as in the course's
sequential "replace only if closer" loop.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .scene.model import Group, Mesh, Plane, Scene, SceneObject, Sphere, Transform, Triangle

F32 = np.float32


@dataclass(frozen=True)
class ObjectTransform:
    """World -> object mapping of a transformed sphere or plane."""

    inverse: np.ndarray  # 4x4 float32, M^-1
    normal_matrix: np.ndarray  # 3x3 float32, (M^-1)^T restricted to 3x3


@dataclass(frozen=True)
class PlacedSphere:
    sphere: Sphere
    order: int
    xform: ObjectTransform | None


@dataclass(frozen=True)
class PlacedPlane:
    plane: Plane
    order: int
    xform: ObjectTransform | None


@dataclass
class TriangleSoup:
    """All triangles in world space. Vertex normals are per corner, (T,3,3)."""

    vertices: np.ndarray = field(default_factory=lambda: np.zeros((0, 3, 3), F32))
    normals: np.ndarray = field(default_factory=lambda: np.zeros((0, 3, 3), F32))
    material: np.ndarray = field(default_factory=lambda: np.zeros(0, np.uint32))
    order: np.ndarray = field(default_factory=lambda: np.zeros(0, np.uint32))

    def __len__(self) -> int:
        return len(self.material)


@dataclass
class FlatScene:
    spheres: list[PlacedSphere]
    planes: list[PlacedPlane]
    triangles: TriangleSoup
    primitive_count: int


def _object_transform(m: np.ndarray) -> ObjectTransform:
    with np.errstate(all="ignore"):
        try:
            inv = np.linalg.inv(m.astype(np.float64))
            if not np.isfinite(inv.astype(np.float32)).all():
                raise np.linalg.LinAlgError
        except np.linalg.LinAlgError:
            # A singular transform (Scale 0): the course's float inverse yields inf/NaN, so
            # rays into the object are NaN: planes miss, spheres are hit at t = 10000 (spec §5);
            # a NaN inverse gives the same here.
            inv = np.full((4, 4), np.nan)
    inv32 = inv.astype(F32)
    return ObjectTransform(inv32, inv32[:3, :3].T.copy())


def _unit(n: np.ndarray) -> np.ndarray:
    with np.errstate(invalid="ignore", divide="ignore"):
        return n / np.sqrt((n[..., 0] * n[..., 0] + n[..., 1] * n[..., 1])
                           + n[..., 2] * n[..., 2])[..., None]


def flatten(scene: Scene) -> FlatScene:
    spheres: list[PlacedSphere] = []
    planes: list[PlacedPlane] = []
    tri_v: list[np.ndarray] = []
    tri_n: list[np.ndarray] = []
    tri_m: list[np.ndarray] = []
    tri_o: list[np.ndarray] = []
    counter = 0

    def add_triangles(v: np.ndarray, n: np.ndarray, material: int, m: np.ndarray | None) -> None:
        nonlocal counter
        if m is not None and not np.isfinite(_object_transform(m).inverse).all():
            # Rays reach the child through M^-1 (spec §5); a singular M makes that inf/NaN and
            # nothing inside is ever hit. Moving the triangles to world space instead would
            # draw them flattened, so they are left out (their file-order numbers still count).
            counter += len(v)
            return
        if m is not None:
            v = (v @ m[:3, :3].T.astype(F32) + m[:3, 3]).astype(F32)
            n = (n @ _object_transform(m).normal_matrix.T).astype(F32)
        count = len(v)
        tri_v.append(v.astype(F32))
        tri_n.append(n.astype(F32))
        tri_m.append(np.full(count, material, np.uint32))
        tri_o.append(np.arange(counter, counter + count, dtype=np.uint32))
        counter += count

    def visit(obj: SceneObject, m: np.ndarray | None) -> None:
        nonlocal counter
        if isinstance(obj, Group):
            for child in obj.objects:
                visit(child, m)
        elif isinstance(obj, Transform):
            visit(obj.child, obj.matrix if m is None else (m @ obj.matrix).astype(F32))
        elif isinstance(obj, Sphere):
            spheres.append(PlacedSphere(obj, counter, None if m is None else _object_transform(m)))
            counter += 1
        elif isinstance(obj, Plane):
            planes.append(PlacedPlane(obj, counter, None if m is None else _object_transform(m)))
            counter += 1
        elif isinstance(obj, Triangle):
            v = np.array([[obj.v0, obj.v1, obj.v2]], dtype=F32)
            face_n = _unit(np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0]).astype(F32))
            add_triangles(v, np.repeat(face_n[:, None, :], 3, axis=1), obj.material, m)
        elif isinstance(obj, Mesh):
            add_triangles(obj.vertices[obj.faces], obj.normals[obj.faces], obj.material, m)

    visit(scene.root, None)
    if tri_v:
        soup = TriangleSoup(np.concatenate(tri_v), np.concatenate(tri_n),
                            np.concatenate(tri_m), np.concatenate(tri_o))
    else:
        soup = TriangleSoup()
    return FlatScene(spheres, planes, soup, counter)
