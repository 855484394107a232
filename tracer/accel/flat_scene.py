"""The scene tree flattened into what the kernel intersects (host side, numpy float32).

Spheres and planes keep their object space: rays go into it through the inverse transform, as in
the course renderer, so a non-uniformly scaled sphere stays an exact ellipsoid (spec §5).
All triangles form one soup. In course mode each transformed TriangleMesh or Triangle keeps its
object space too, as an instance the ray is moved into as the course does (bit for bit the
course's hits, which world-space triangles miss by rounding far from the origin), with nested
Transforms one level each. Otherwise (robust mode, float64) transformed triangles are moved to
world space once, with their vertex normals multiplied by M^-T but left unnormalized, so that
interpolating and then normalizing gives normalize(M^-T · normalize(interpolated)) up to
rounding.

Every primitive gets its file-order number: ties in t go to the earlier one, as in the course's
sequential "replace only if closer" loop. A soup records which of its triangles form each
TriangleMesh (the course intersects a mesh through its own octree, tracer.accel.octree).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..scene.model import Group, Mesh, Plane, Scene, SceneObject, Sphere, Transform, Triangle
from .matrices import inverse3, inverse4

F32 = np.float32


@dataclass(frozen=True)
class ObjectTransform:
    """World -> object mapping of a transformed primitive: one level per Transform, outermost
    first, as the course applies them one after the other (course mode), or the composed
    matrix as one level."""

    inverses: tuple[np.ndarray, ...]  # 4x4 float32 M^-1 per level
    normal_matrices: tuple[np.ndarray, ...]  # 3x3 float32 ((M3)^-1)^T per level

    @property
    def finite(self) -> bool:
        return all(np.isfinite(m).all() for m in self.inverses + self.normal_matrices)


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


NO_INSTANCE = 0xFFFFFFFF


@dataclass
class TriangleSoup:
    """All triangles. Vertex normals are per corner, (T,3,3). In course mode a transformed
    triangle keeps its object space: it belongs to an instance (FlatScene.instances) that
    rays enter through its inverse, and `bounds` holds where it lies in world space."""

    vertices: np.ndarray = field(default_factory=lambda: np.zeros((0, 3, 3), F32))
    normals: np.ndarray = field(default_factory=lambda: np.zeros((0, 3, 3), F32))
    material: np.ndarray = field(default_factory=lambda: np.zeros(0, np.uint32))
    order: np.ndarray = field(default_factory=lambda: np.zeros(0, np.uint32))
    instance: np.ndarray = field(default_factory=lambda: np.zeros(0, np.uint32))
    bounds: np.ndarray | None = None  # (T,3,3) world-space vertices where they differ
    meshes: list[tuple[int, int]] = field(default_factory=list)  # (first, count) per mesh

    def __len__(self) -> int:
        return len(self.material)


@dataclass
class FlatScene:
    spheres: list[PlacedSphere]
    planes: list[PlacedPlane]
    triangles: TriangleSoup
    primitive_count: int
    instances: list[ObjectTransform] = field(default_factory=list)


def _level(m: np.ndarray, course: bool) -> tuple[np.ndarray, np.ndarray]:
    """M^-1 and ((M3)^-1)^T: the course's float32 cofactor inverses (course), or float64 ones
    rounded to float32."""
    with np.errstate(all="ignore"):
        if course:
            inv, normal = inverse4(m), inverse3(m[:3, :3]).T.copy()
        else:
            try:
                inv = np.linalg.inv(m.astype(np.float64)).astype(F32)
            except np.linalg.LinAlgError:
                inv = np.full((4, 4), np.nan, F32)
            normal = inv[:3, :3].T.copy()
    if not (np.isfinite(inv).all() and np.isfinite(normal).all()):
        # A singular transform (Scale 0): the course's float inverse yields inf/NaN, so rays
        # into the object are NaN: planes and triangles miss, spheres are hit at t = 10000
        # (spec §5); a NaN inverse gives the same here.
        inv, normal = np.full((4, 4), np.nan, F32), np.full((3, 3), np.nan, F32)
    return inv, normal


def _object_transform(chain: tuple[np.ndarray, ...], course: bool) -> ObjectTransform | None:
    """The transform of a primitive under the Transforms `chain` (outermost first)."""
    if not chain:
        return None
    if not course:
        chain = (_composed(chain),)
    levels = [_level(m, course) for m in chain]
    return ObjectTransform(tuple(i for i, _ in levels), tuple(n for _, n in levels))


def _composed(chain: tuple[np.ndarray, ...]) -> np.ndarray:
    m = chain[0]
    for nxt in chain[1:]:
        m = (m @ nxt).astype(F32)
    return m


def _unit(n: np.ndarray) -> np.ndarray:
    with np.errstate(invalid="ignore", divide="ignore"):
        return n / np.sqrt((n[..., 0] * n[..., 0] + n[..., 1] * n[..., 1])
                           + n[..., 2] * n[..., 2])[..., None]


def _world_points(v: np.ndarray, xf: ObjectTransform) -> np.ndarray:
    """Where object-space points lie in world space for rays that reach them through xf's
    float32 inverses: their images under the exact (float64) inverses of those inverses,
    outermost level last."""
    p = v.astype(np.float64)
    for inverse in reversed(xf.inverses):
        m = np.linalg.inv(inverse.astype(np.float64))
        h = p @ m[:3, :3].T + m[:3, 3]
        w = p @ m[3, :3] + m[3, 3]
        p = h / w[..., None]
    return p.astype(F32)


class _SoupBuilder:
    def __init__(self) -> None:
        self.parts: list[tuple[np.ndarray, ...]] = []
        self.meshes: list[tuple[int, int]] = []
        self.size = 0
        self.instanced = False

    def add(self, v, n, material: int, first_order: int, mesh: bool,
            instance: int = NO_INSTANCE, bounds: np.ndarray | None = None) -> None:
        count = len(v)
        if mesh:
            self.meshes.append((self.size, count))
        self.instanced |= bounds is not None
        self.parts.append((v.astype(F32), n.astype(F32), np.full(count, material, np.uint32),
                           np.arange(first_order, first_order + count, dtype=np.uint32),
                           np.full(count, instance, np.uint32),
                           (v if bounds is None else bounds).astype(F32)))
        self.size += count

    def soup(self) -> TriangleSoup:
        if not self.parts:
            return TriangleSoup()
        v, n, m, o, inst, bounds = (np.concatenate(x) for x in zip(*self.parts))
        return TriangleSoup(v, n, m, o, inst, bounds if self.instanced else None, self.meshes)


def flatten(scene: Scene, course: bool = False) -> FlatScene:
    """course: the course's float32 inverses, and transformed triangles stay in object space
    (instances); else float64 inverses, and transformed triangles move to world space."""
    spheres: list[PlacedSphere] = []
    planes: list[PlacedPlane] = []
    soup = _SoupBuilder()
    instances: list[ObjectTransform] = []
    counter = 0

    def add_triangles(v: np.ndarray, n: np.ndarray, material: int,
                      chain: tuple[np.ndarray, ...], mesh: bool) -> None:
        nonlocal counter
        xf = _object_transform(chain, course)
        if xf is not None and not xf.finite:
            # Rays reach the child through M^-1 (spec §5); a singular M makes that inf/NaN and
            # no triangle inside is ever hit. Moving the triangles to world space instead would
            # draw them flattened, so they are left out (their file-order numbers still count).
            counter += len(v)
            return
        if xf is not None and course:
            instances.append(xf)
            soup.add(v, n, material, counter, mesh, len(instances) - 1, _world_points(v, xf))
        elif xf is not None:
            m = _composed(chain)
            soup.add((v @ m[:3, :3].T.astype(F32) + m[:3, 3]).astype(F32),
                     (n @ xf.normal_matrices[0].T).astype(F32), material, counter, mesh)
        else:
            soup.add(v, n, material, counter, mesh)
        counter += len(v)

    def visit(obj: SceneObject, chain: tuple[np.ndarray, ...]) -> None:
        nonlocal counter
        if isinstance(obj, Group):
            for child in obj.objects:
                visit(child, chain)
        elif isinstance(obj, Transform):
            visit(obj.child, chain + (obj.matrix,))
        elif isinstance(obj, Sphere):
            spheres.append(PlacedSphere(obj, counter, _object_transform(chain, course)))
            counter += 1
        elif isinstance(obj, Plane):
            planes.append(PlacedPlane(obj, counter, _object_transform(chain, course)))
            counter += 1
        elif isinstance(obj, Triangle):
            v = np.array([[obj.v0, obj.v1, obj.v2]], dtype=F32)
            face_n = _unit(np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0]).astype(F32))
            add_triangles(v, np.repeat(face_n[:, None, :], 3, axis=1), obj.material, chain,
                          False)
        elif isinstance(obj, Mesh):
            add_triangles(obj.vertices[obj.faces], obj.normals[obj.faces], obj.material, chain,
                          len(obj.faces) > 0)

    visit(scene.root, ())
    return FlatScene(spheres, planes, soup.soup(), counter, instances)
