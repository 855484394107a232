"""Auxiliary images: the parts of a course-mode color image, from the same rays.

A render asked for `aux` names also returns, per pixel of its primary ray, what the hit was
and the Phong terms the color is made of (spec §6), so that a candidate's image can be
explained in terms of them (the harness's findings). The color image itself is unchanged:

    color = ((Σ over lights i in file order, not shadow[i], of diffuse[i] + specular[i])
             + reflection) + ambient

on every pixel whose primary ray hits (object >= 0), bit for bit in float32 (the kernel adds
in this order; `compose` does it again in numpy). Per-light images are (h, w, L[, 3]).

* object: the hit object's index among the scene's leaves (spheres, planes, triangles,
  meshes) in file order, -1 where the ray misses; material: its material index, -1 on a miss
* ambient: ambient ⊙ kd; diffuse, specular: each light's unshadowed terms
  max(N·L, 0)·I ⊙ kd and rl^shininess·I ⊙ ks; shadow: whether that light's shadow ray is
  blocked (always False without -shadows)
* cos_nl: N·L (unclamped, the sign tells the side the light is on), cos_rl: R·L clamped at 0,
  intensity: the light's I at the hit (falloff applied)
* reflection: ks ⊙ trace(reflected ray), 0 where there is no mirror bounce; mirror_depth: the
  number of mirror bounces the pixel's chain followed (0..-bounces)

Only course mode, without -jitter and -filter (a pixel is then one primary ray).
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..scene.model import Group, Mesh, Plane, Scene, SceneObject, Sphere, Transform, Triangle

PER_PIXEL = ("object", "material", "ambient", "reflection", "mirror_depth")
PER_LIGHT = ("diffuse", "specular", "shadow", "cos_nl", "cos_rl", "intensity")
AUX_KINDS = PER_PIXEL + PER_LIGHT
INTEGER = ("object", "material", "mirror_depth", "shadow")
CHANNELS = {"ambient": 3, "reflection": 3, "diffuse": 3, "specular": 3, "intensity": 3}
NO_ORDER = 0xFFFFFFFF  # a primary ray's primitive order where it misses


@dataclass(frozen=True)
class SceneObjectInfo:
    """One leaf object of the scene, as the object image numbers it."""

    index: int
    kind: str  # sphere, plane, triangle, mesh
    material: int
    line: int
    transformed: bool
    mesh: Path | None  # a mesh's OBJ file
    first_order: int  # its primitives' file-order numbers: first_order .. first_order+count-1
    count: int

    def describe(self) -> str:
        what = f"{self.kind} {self.mesh.name}" if self.mesh else self.kind
        moved = ", transformed" if self.transformed else ""
        return f"object {self.index} ({what}, line {self.line}{moved}, material {self.material})"


def scene_objects(scene: Scene) -> list[SceneObjectInfo]:
    """The scene's leaf objects in file order, numbered as the tracer numbers their primitives
    (one per sphere, plane and triangle, one per face of a mesh)."""
    found: list[SceneObjectInfo] = []
    order = 0

    def visit(obj: SceneObject, transformed: bool) -> None:
        nonlocal order
        if isinstance(obj, Group):
            for child in obj.objects:
                visit(child, transformed)
            return
        if isinstance(obj, Transform):
            visit(obj.child, True)
            return
        count = len(obj.faces) if isinstance(obj, Mesh) else 1
        kind = {Sphere: "sphere", Plane: "plane", Triangle: "triangle", Mesh: "mesh"}[type(obj)]
        found.append(SceneObjectInfo(len(found), kind, obj.material, obj.line, transformed,
                                     obj.path if isinstance(obj, Mesh) else None, order, count))
        order += count

    visit(scene.root, False)
    return found


def object_image(order: np.ndarray, objects: list[SceneObjectInfo]) -> np.ndarray:
    """Per pixel the object index of a primitive-order image (NO_ORDER: -1)."""
    starts = np.array([o.first_order for o in objects], np.int64)
    index = np.searchsorted(starts, order.astype(np.int64), side="right") - 1
    return np.where(order == NO_ORDER, -1, index).astype(np.int32)


def check_aux_request(opts) -> None:
    """ValueError where auxiliary images are asked for a render that cannot have them."""
    unknown = [k for k in opts.aux if k not in AUX_KINDS]
    if unknown:
        raise ValueError(f"unknown auxiliary images {unknown} (expected some of {AUX_KINDS})")
    if opts.aux and (opts.mode != "course" or opts.jitter or opts.filter):
        raise ValueError("auxiliary images need a course-mode render without -jitter and "
                         "-filter (one primary ray per pixel)")


def compose(aux: dict[str, np.ndarray], background: np.ndarray) -> np.ndarray:
    """The color image from its parts, in the kernel's order of float32 additions; where the
    primary ray misses, `background` (the color image's own values there)."""
    lit = ~aux["shadow"].astype(bool)
    direct = np.zeros(aux["ambient"].shape, np.float32)
    for i in range(aux["shadow"].shape[2]):
        term = aux["diffuse"][:, :, i] + aux["specular"][:, :, i]
        direct = np.where(lit[:, :, i, None], direct + term, direct)
    color = (direct + aux["reflection"]) + aux["ambient"]
    return np.where((aux["object"] >= 0)[..., None], color, background)


@dataclass(frozen=True)
class AuxBuffer:
    """One kernel output of an auxiliary image: a whole image, or one light's."""

    name: str
    light: int | None

    @property
    def key(self) -> str:
        return self.name if self.light is None else f"{self.name}:{self.light}"

    @property
    def channels(self) -> int:
        return CHANNELS.get(self.name, 1)

    @property
    def integer(self) -> bool:
        return self.name in INTEGER


def aux_buffers(aux: tuple[str, ...], n_lights: int) -> list[AuxBuffer]:
    """The kernel outputs of the asked images, "object" always (it tells the misses)."""
    return [AuxBuffer(name, None) for name in PER_PIXEL if name in aux or name == "object"] + \
        [AuxBuffer(name, i) for name in PER_LIGHT if name in aux for i in range(n_lights)]


def kernel_outputs(record: dict, buffers: list[AuxBuffer], T) -> dict:
    """The recorded values the buffers take, masks as 0/1 integers."""
    out = {}
    for b in buffers:
        value = record[b.key]
        if isinstance(value, T.Bool):
            value = T.UInt32(value)
        out[b.key] = value
    return out


def assemble(raw: dict[str, np.ndarray], buffers: list[AuxBuffer], shape: tuple[int, int],
             objects: list[SceneObjectInfo], names: tuple[str, ...]) -> dict[str, np.ndarray]:
    """The images `names`, and "object" always, from the buffers' top-down row-major values:
    per-light images
    stacked on axis 2 (of length 0 in a scene without lights); where the primary ray misses,
    values 0 and object and material -1."""
    order = raw["object"].reshape(shape)
    hit = order != NO_ORDER
    parts: dict[str, list[np.ndarray]] = {}
    for b in buffers:
        v = raw[b.key].reshape(shape + ((b.channels,) if b.channels > 1 else ()))
        parts.setdefault(b.name, []).append(v)
    out = {}
    for name, values in parts.items():
        v = values[0] if name in PER_PIXEL else np.stack(values, axis=2)
        if name in INTEGER:
            v = v.astype(np.int32)
        miss = -1 if name == "material" else 0
        out[name] = np.where(hit.reshape(shape + (1,) * (v.ndim - 2)), v, miss).astype(v.dtype)
    out["object"] = object_image(order, objects)
    for name in PER_LIGHT:
        if name in names and name not in out:  # no lights
            out[name] = np.zeros(shape + (0,) + ((CHANNELS[name],) if name in CHANNELS else ()),
                                 np.int32 if name in INTEGER else np.float32)
    return out
