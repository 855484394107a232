"""Course scene description (tracer.scene) -> Mitsuba scene description.

`plan(scene, settings)` builds a plain dictionary in `mi.load_dict` layout whose leaves are plain
Python values, 4x4 numpy matrices (key "to_world") and `MeshData`; `load_dict_form(plan)` turns
those into Mitsuba objects for `mi.load_dict`, and export.py writes the same plan as XML. What
goes in, and why:

* Sphere -> native `sphere` (center, radius). Under a transform that is a similarity (rotation,
  reflection, uniform scale, translation) the sphere stays a sphere with the moved centre and
  scaled radius; under any other transform it goes into a `shapegroup` and an `instance`
  carries the matrix, so Mitsuba intersects in object space exactly like the course (rays
  through M^-1, normal normalize(M^-T n)): an exact ellipsoid. (A `sphere` with a non-uniform
  `to_world` is silently wrong in Mitsuba.)
* TriangleMesh / Triangle -> a mesh built from numpy with the course's vertex normals (Triangle:
  all three = normalize(cross(v1-v0, v2-v0)); triangles of one material share one mesh).
  Transformed meshes get their `to_world` applied on the host (float64, then float32): a mesh
  created from Python ignores `to_world`, and the `ply`/`obj` loaders, which do apply it,
  renormalize each vertex normal. The world normals are M^-T n left unnormalized on purpose:
  Mitsuba's shading normal normalize(Σ b_i n_i) then equals the course's
  normalize(M^-T normalize(Σ b_i n_i)) for any M, smooth meshes under non-uniform scale included.
* Plane -> a large two-sided `disk` of radius PLANE_SCALE times the scene's extent, centred at
  the foot of the scene's centre on the plane; the sensor's far_clip reaches past its rim.
  (Not a `rectangle`: in Mitsuba 3.9.1 that is a two-triangle mesh, which Embree intersects in
  float32 with an error in t proportional to the triangle's size -- measured 6e-5 at a
  half-size of 1e4 and 1% at 1e6 for a tilted plane. The disk is intersected analytically in
  its own frame and stays exact at any size; both are the same infinite plane to the course.) A
  bare plane's normal as written can have any length (the course uses it raw); the disk's
  normal is unit, so the plane's material copy carries normal_scale = |n|. A transformed plane
  is the set (M^-T n)·x = d', with the unit normal normalize(M^-T n), as in the course.
* PointLight -> `point` with intensity = color / falloff (so intensity / d^2 is the course's
  color / ((d*falloff)*d); falloff 0 gives inf or NaN like the course). DirectionalLight ->
  `directional` with the parsed (normalized) direction and irradiance = color. Keys light_000,
  light_001, ... keep the file order (the integrator sums lights in that order).
* Materials -> `course_phong`, only the ones some object uses; integrator `course_whitted`;
  sensor `course_camera`.
Nothing else goes in: no unused materials, and no light whose colour is exactly zero where that
provably adds exactly zero to every pixel.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from raycheck.tracer.scene.model import (
    Group,
    Mesh,
    Plane,
    PointLight,
    Scene,
    SceneObject,
    Sphere,
    Transform,
    Triangle,
)
from raycheck.tracer.scene.request import RenderRequest

F32 = np.float32
FLT_MAX = float(np.finfo(np.float32).max)
# Radius of a plane's disk in units of the scene extent. The course plane is infinite; a finite
# one differs only for rays that would hit it farther than this, i.e. within about
# (camera height / radius) radians of the horizon: ~1e-7 rad, 1/10000 of a pixel at 800 px.
PLANE_SCALE = 1.0e6
MAX_PLANE_RADIUS = 1.0e30  # keeps the disk's matrix and the far clip finite in float32
SIMILARITY_TOLERANCE = 1e-5  # relative: float32 rotation matrices are orthogonal to ~1e-7


def sampler_seed(seed: int, launch: int = 0) -> int:
    """The seed the sampler gets (below 2^32) for a request's seed (below 2^64, as the tracer
    takes) and the number of a launch (render.py: its passes and bands): each launch draws
    its own samples. (Mitsuba mixes it with the sampler's own seed, the request's seed modulo
    2^32.)"""
    return (seed * 1_000_003 + launch) & 0xFFFFFFFF


@dataclass(frozen=True)
class Settings(RenderRequest):
    """What the Mitsuba scene needs: the render request, and which ray offsets to use."""

    offsets: str = "course"  # or "mitsuba": Mitsuba's spawn_ray offsets

    @property
    def film_size(self) -> tuple[int, int]:
        k = 3 if self.filter else 1  # -filter renders 3w x 3h sub-pixels (spec §9)
        return self.width * k, self.height * k


@dataclass(frozen=True, eq=False)
class MeshData:
    """A triangle mesh in object space: float32 vertices (V,3), int faces (F,3), course vertex
    normals (V,3), and the object->world matrix (float64 4x4) or None."""

    name: str
    vertices: np.ndarray
    faces: np.ndarray
    normals: np.ndarray
    matrix: np.ndarray | None = None

    def world(self) -> tuple[np.ndarray, np.ndarray]:
        """World-space vertices and (unnormalized) world normals M^-T n, float32."""
        if self.matrix is None:
            return self.vertices, self.normals
        m3 = self.matrix[:3, :3]
        v = self.vertices.astype(np.float64) @ m3.T + self.matrix[:3, 3]
        with np.errstate(all="ignore"):
            n = self.normals.astype(np.float64) @ np.linalg.inv(m3)  # rows: (M^-T n)^T
        return v.astype(F32), n.astype(F32)

    @property
    def flat(self) -> bool:
        """The three vertex normals of every face are equal (it shades flat), so renormalizing
        each after a transform, as Mitsuba's loaders do, changes nothing."""
        n = self.normals[self.faces]
        with np.errstate(invalid="ignore"):
            return bool(np.all(np.abs(n[:, 1] - n[:, 0]) <= 1e-6)
                        and np.all(np.abs(n[:, 2] - n[:, 0]) <= 1e-6))


# --------------------------------------------------------------------------- small geometry
def _normalize32(v: np.ndarray) -> np.ndarray:
    v = np.asarray(v, dtype=F32)
    with np.errstate(all="ignore"):
        return v / np.sqrt((v[..., 0] * v[..., 0] + v[..., 1] * v[..., 1])
                           + v[..., 2] * v[..., 2])[..., None]


def triangle_normal(t: Triangle) -> np.ndarray:
    """normalize(cross(v1 - v0, v2 - v0)) in float32 (spec §2 Triangle)."""
    v0, v1, v2 = (np.array(p, dtype=F32) for p in (t.v0, t.v1, t.v2))
    e1, e2 = v1 - v0, v2 - v0
    c = np.array([e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                  e1[0] * e2[1] - e1[1] * e2[0]], dtype=F32)
    return _normalize32(c)


def singular(m: np.ndarray) -> bool:
    """A transform without a finite inverse (e.g. Scale 0 1 1)."""
    if not np.all(np.isfinite(m)):
        return True
    det = float(np.linalg.det(m.astype(np.float64)))
    return det == 0.0 or not math.isfinite(det)


def similarity_scale(m: np.ndarray) -> float | None:
    """s if the 3x3 part of m is s times an orthogonal matrix, else None."""
    m3 = m[:3, :3]
    g = m3.T @ m3
    s2 = float(np.trace(g)) / 3.0
    if not math.isfinite(s2) or s2 <= 0:
        return None
    if np.max(np.abs(g - s2 * np.eye(3))) > SIMILARITY_TOLERANCE * s2:
        return None
    return math.sqrt(s2)


def _ref(key: str) -> dict[str, str]:
    return {"type": "ref", "id": key}


def _rgb(c) -> dict[str, Any]:
    return {"type": "rgb", "value": [float(x) for x in c]}


# --------------------------------------------------------------------------- the planner
class _Planner:
    def __init__(self, scene: Scene, settings: Settings) -> None:
        self.scene = scene
        self.settings = settings
        self.shapes: dict[str, dict] = {}
        self.groups: dict[str, dict] = {}
        self.materials_used: dict[tuple[int, float], str] = {}
        self.triangles: dict[int, list[tuple[np.ndarray, np.ndarray]]] = {}
        self.planes: list[tuple[np.ndarray, float, float, int]] = []  # normal, d, scale, mat
        self.bbox_points: list[np.ndarray] = [np.array(scene.camera.center, dtype=np.float64)]

    # -- materials ---------------------------------------------------------------------------
    def material(self, index: int, normal_scale: float = 1.0) -> dict[str, str]:
        key = (index, normal_scale)
        if key not in self.materials_used:
            name = f"mat_{index:03d}" if normal_scale == 1.0 else \
                f"mat_{index:03d}_n{len(self.materials_used):03d}"
            self.materials_used[key] = name
        return _ref(self.materials_used[key])

    def material_dicts(self) -> dict[str, dict]:
        out = {}
        for (index, normal_scale), name in sorted(self.materials_used.items(),
                                                  key=lambda kv: kv[1]):
            m = self.scene.materials[index]
            d = {"type": "course_phong", "kd": _rgb(m.diffuse), "ks": _rgb(m.specular),
                 "shininess": float(m.shininess)}
            if normal_scale != 1.0:
                d["normal_scale"] = float(normal_scale)
            out[name] = d
        return out

    # -- objects -------------------------------------------------------------------------------
    def visit(self, obj: SceneObject, matrix: np.ndarray | None) -> None:
        if isinstance(obj, Group):
            for child in obj.objects:
                self.visit(child, matrix)
        elif isinstance(obj, Transform):
            m = obj.matrix.astype(np.float64)
            if singular(m):
                # rays reach the child through M^-1, which is inf/NaN for a singular M in the
                # course's float arithmetic: nothing below is ever hit (spec §5)
                return
            self.visit(obj.child, m if matrix is None else matrix @ m)
        elif isinstance(obj, Sphere):
            self.sphere(obj, matrix)
        elif isinstance(obj, Plane):
            self.plane(obj, matrix)
        elif isinstance(obj, Triangle):
            self.triangle(obj, matrix)
        elif isinstance(obj, Mesh):
            self.mesh(obj, matrix)
        else:  # pragma: no cover - the parser produces nothing else
            raise TypeError(f"unknown scene object {type(obj).__name__}")

    def _add_shape(self, d: dict) -> None:
        self.shapes[f"shape_{len(self.shapes):04d}"] = d

    def sphere(self, s: Sphere, matrix: np.ndarray | None) -> None:
        r = abs(float(s.radius))  # the course's quadratic only sees r^2
        if r == 0.0 or not math.isfinite(r):
            return  # never hit (or only along measure-zero rays)
        c = np.array(s.center, dtype=np.float64)
        scale = 1.0 if matrix is None else similarity_scale(matrix)
        if scale is not None:
            center = c if matrix is None else matrix[:3, :3] @ c + matrix[:3, 3]
            radius = r * scale
            self.bbox_points += [center - radius, center + radius]
            self._add_shape({"type": "sphere", "center": [float(x) for x in center],
                             "radius": float(radius), "bsdf": self.material(s.material)})
            return
        assert matrix is not None  # scale is 1.0 without one, and that returned above
        group = f"group_{len(self.groups):03d}"
        self.groups[group] = {"type": "shapegroup",
                              "sphere": {"type": "sphere", "center": [float(x) for x in c],
                                         "radius": r, "bsdf": self.material(s.material)}}
        corners = np.array([[x, y, z] for x in (-r, r) for y in (-r, r) for z in (-r, r)]) + c
        self.bbox_points += list(corners @ matrix[:3, :3].T + matrix[:3, 3])
        self._add_shape({"type": "instance", "shapegroup": _ref(group), "to_world": matrix})

    def plane(self, p: Plane, matrix: np.ndarray | None) -> None:
        n = np.array(p.normal, dtype=np.float64)
        d = float(p.offset)
        if matrix is None:
            scale = float(np.linalg.norm(np.array(p.normal, dtype=F32).astype(np.float64)))
            # the course's raw normal, as a float32 length (exact for 0 2 0 and the like)
            scale = float(F32(scale))
        else:
            # {x : n·(M^-1 x) = d} = {x : (M^-T n)·x = d + (M^-T n)·t}; unit normal in the course
            inv = np.linalg.inv(matrix)
            n_world = inv[:3, :3].T @ n
            d = d - float(n @ inv[:3, 3])
            n = n_world
            scale = 1.0
        length = float(np.linalg.norm(n))
        if not (length > 0.0 and math.isfinite(length) and math.isfinite(d)):
            return  # a zero normal is never hit (t is inf or NaN, spec §5)
        self.planes.append((n / length, d / length, scale, p.material))

    def triangle(self, t: Triangle, matrix: np.ndarray | None) -> None:
        v = np.array([t.v0, t.v1, t.v2], dtype=F32)
        n = np.repeat(triangle_normal(t)[None, :], 3, axis=0)
        data = MeshData("tri", v, np.array([[0, 1, 2]]), n, matrix)
        wv, wn = data.world()
        self.bbox_points += list(wv.astype(np.float64))
        self.triangles.setdefault(t.material, []).append((wv, wn))

    def mesh(self, m: Mesh, matrix: np.ndarray | None) -> None:
        name = f"mesh_{len(self.shapes):04d}"
        data = MeshData(name, m.vertices.astype(F32), m.faces.astype(np.int64),
                        m.normals.astype(F32), matrix)
        wv, _ = data.world()
        used = wv[np.unique(m.faces)]
        self.bbox_points += [used.min(axis=0).astype(np.float64),
                             used.max(axis=0).astype(np.float64)]
        self._add_shape({"type": "mesh", "data": data, "bsdf": self.material(m.material)})

    def flush_triangles(self) -> None:
        for material, tris in sorted(self.triangles.items()):
            v = np.concatenate([wv for wv, _ in tris]).astype(F32)
            n = np.concatenate([wn for _, wn in tris]).astype(F32)
            faces = np.arange(len(v), dtype=np.int64).reshape(-1, 3)
            data = MeshData(f"triangles_{material:03d}", v, faces, n, None)
            self._add_shape({"type": "mesh", "data": data, "bsdf": self.material(material)})

    def extent(self) -> tuple[np.ndarray, float]:
        pts = np.array([p for p in self.bbox_points if np.all(np.isfinite(p))]
                       or [np.zeros(3)])
        lo, hi = pts.min(axis=0), pts.max(axis=0)
        with np.errstate(over="ignore"):
            size = float(np.linalg.norm(hi - lo))
        return (lo + hi) / 2.0, min(max(size, 1.0), MAX_PLANE_RADIUS)

    def flush_planes(self) -> float | None:
        """Disks for the planes; returns the far_clip that reaches past all of them."""
        if not self.planes:
            return None
        centre, size = self.extent()
        half = min(PLANE_SCALE * size, MAX_PLANE_RADIUS)
        for n_hat, d, scale, material in self.planes:
            foot = centre - (float(n_hat @ centre) - d) * n_hat
            helper = np.array([1.0, 0.0, 0.0]) if abs(n_hat[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
            s = np.cross(n_hat, helper)
            s /= np.linalg.norm(s)
            t = np.cross(n_hat, s)
            to_world = np.eye(4)
            to_world[:3, 0] = s * half
            to_world[:3, 1] = t * half
            # z scaled like x and y: a similarity keeps Mitsuba's float32 inverse accurate
            # (with z unscaled the matrix would have a condition number of ~1e6)
            to_world[:3, 2] = n_hat * half
            to_world[:3, 3] = foot
            self._add_shape({"type": "disk", "to_world": to_world,
                             "bsdf": self.material(material, scale)})
        # far enough to reach every rim point from anywhere within the scene's extent
        return min(2.0 * half + 2.0 * size, FLT_MAX)

    # -- lights ----------------------------------------------------------------------------
    def lights(self) -> dict[str, dict]:
        used = [self.scene.materials[i] for i, _ in self.materials_used]
        any_negative_shininess = any(m.shininess < 0 for m in used)
        out = {}
        for k, light in enumerate(self.scene.lights):
            color = np.array(light.color, dtype=F32)
            if isinstance(light, PointLight):
                # zero colour adds exactly 0 unless the intensity is 0/0 (falloff 0) or a
                # powf(0, negative) = inf multiplies it
                if not color.any() and light.falloff > 0 and not any_negative_shininess:
                    continue
                with np.errstate(all="ignore"):
                    intensity = color / F32(light.falloff)
                out[f"light_{k:03d}"] = {"type": "point",
                                         "position": [float(x) for x in light.position],
                                         "intensity": _rgb(intensity)}
            else:
                if not color.any() and not any_negative_shininess \
                        and np.all(np.isfinite(light.direction)):
                    continue
                out[f"light_{k:03d}"] = {"type": "directional",
                                         "direction": [float(x) for x in light.direction],
                                         "irradiance": _rgb(color)}
        return out


def plan(scene: Scene, settings: Settings) -> dict[str, Any]:
    """The Mitsuba scene for `scene` rendered with `settings`, as a plain dictionary."""
    p = _Planner(scene, settings)
    p.visit(scene.root, None)
    p.flush_triangles()
    for light in scene.lights:
        if isinstance(light, PointLight):
            p.bbox_points.append(np.array(light.position, dtype=np.float64))
    far_clip = p.flush_planes()
    lights = p.lights()

    width, height = settings.film_size
    cam = scene.camera
    sensor: dict[str, Any] = {
        "type": "course_camera",
        "center": [float(x) for x in cam.center],
        "direction": [float(x) for x in cam.direction],
        "up": [float(x) for x in cam.up],
        "angle": float(cam.angle_deg),
        "film": {"type": "hdrfilm", "width": width, "height": height, "pixel_format": "rgb",
                 "component_format": "float32", "sample_border": False,
                 "rfilter": {"type": "box"}},
    }
    if settings.jitter:
        sensor["jitter"] = True
        sensor["sampler"] = {"type": "independent", "sample_count": settings.samples,
                             "seed": settings.seed % 2**32}
    else:
        # one sample at the exact pixel position (offset 0.5, which the camera floors away)
        sensor["sampler"] = {"type": "stratified", "sample_count": 1, "jitter": False}
    if far_clip is not None:
        sensor["far_clip"] = far_clip

    bg = scene.background
    integrator: dict[str, Any] = {"type": "course_whitted", "ambient": _rgb(bg.ambient)}
    if settings.bounces:
        integrator["bounces"] = settings.bounces
    if settings.shadows and lights:
        integrator["shadows"] = True
    if settings.offsets != "course":
        integrator["offsets"] = settings.offsets
    if bg.cube_map is not None:
        integrator["cube_map"] = str(Path(bg.cube_map.folder).resolve())
    else:
        integrator["background"] = _rgb(bg.color)
    if not settings.wants("color"):
        integrator["color"] = False
    if settings.wants("normals"):
        integrator["normals"] = True
    if settings.wants("depth"):
        integrator["depth"] = True
        integrator["depth_min"] = float(settings.depth_min)
        integrator["depth_max"] = float(settings.depth_max)

    out: dict[str, Any] = {"type": "scene", "integrator": integrator, "camera": sensor}
    out.update(p.material_dicts())
    out.update(p.groups)
    out.update(lights)
    out.update(p.shapes)
    return out


# --------------------------------------------------------------------------- to Mitsuba objects
def mesh_object(data: MeshData, bsdf: Any):
    """A Mitsuba mesh from world-space numpy arrays with the course's normals."""
    import mitsuba as mi

    v, n = data.world()
    props = mi.Properties()
    if bsdf is not None:
        props["bsdf"] = bsdf
    mesh = mi.Mesh(data.name, len(v), len(data.faces), props, has_vertex_normals=True)
    params = mi.traverse(mesh)
    params["vertex_positions"] = mi.Float(np.ascontiguousarray(v, dtype=F32).reshape(-1))
    params["faces"] = mi.UInt32(np.ascontiguousarray(data.faces, dtype=np.uint32).reshape(-1))
    params["vertex_normals"] = mi.Float(np.ascontiguousarray(n, dtype=F32).reshape(-1))
    params.update()
    return mesh


def load_dict_form(plan_dict: dict[str, Any]) -> dict[str, Any]:
    """The plan with matrices as Mitsuba transforms, meshes as Mitsuba meshes and every
    material reference replaced by the one shared BSDF object."""
    import mitsuba as mi

    bsdfs = {k: mi.load_dict(v) for k, v in plan_dict.items()
             if isinstance(v, dict) and v.get("type") == "course_phong"}
    return {k: _converted(v, k, bsdfs) for k, v in plan_dict.items() if k not in bsdfs}


def _converted(value: Any, key: str, bsdfs: dict[str, Any]) -> Any:
    """A plan value in load_dict's form. A module-level function, not a closure that calls
    itself: such a closure is a reference cycle holding `bsdfs`, which kept every scene's BSDFs
    alive until the next full garbage collection."""
    import mitsuba as mi

    if isinstance(value, dict):
        if value.get("type") == "mesh":
            return mesh_object(value["data"], bsdfs[value["bsdf"]["id"]])
        if value.get("type") == "ref" and value["id"] in bsdfs:
            return bsdfs[value["id"]]
        return {k: _converted(v, k, bsdfs) for k, v in value.items()}
    if key == "to_world" and isinstance(value, np.ndarray):
        return mi.ScalarTransform4f(value.astype(np.float32))
    return value
