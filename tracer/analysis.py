"""What a scene uses and which course flags can change its image (`raycheck info`).

The comparison harness uses this too: a feature a scene cannot exercise is not rendered or
compared, and its skip reason comes from here.
"""
from __future__ import annotations

from collections import Counter
from dataclasses import dataclass, field

from .scene.model import (
    DirectionalLight,
    Group,
    Mesh,
    Plane,
    Scene,
    SceneObject,
    Sphere,
    Transform,
    Triangle,
    reflective_mask,
)


@dataclass(frozen=True)
class SceneInfo:
    primitives: dict[str, int]  # sphere, plane, triangle, mesh
    mesh_triangles: int
    transforms: int
    max_depth: int
    lights: dict[str, int]  # directional, point
    materials: int
    used_materials: tuple[int, ...]
    reflective_materials: tuple[int, ...]  # used ones with |ks| > 0.1
    cube_map: bool
    ambient_forced: bool
    flag_effects: dict[str, str] = field(default_factory=dict)  # flag -> why it matters / not

    def matters(self, flag: str) -> bool:
        return not self.flag_effects[flag].startswith("no effect")

    @property
    def total_triangles(self) -> int:
        return self.primitives.get("triangle", 0) + self.mesh_triangles


def analyze(scene: Scene) -> SceneInfo:
    prims: Counter[str] = Counter()
    used: set[int] = set()
    mesh_tris = 0
    transforms = 0
    max_depth = 0

    def visit(obj: SceneObject, depth: int) -> None:
        nonlocal mesh_tris, transforms, max_depth
        max_depth = max(max_depth, depth)
        if isinstance(obj, Group):
            for child in obj.objects:
                visit(child, depth + 1)
        elif isinstance(obj, Transform):
            transforms += 1
            visit(obj.child, depth + 1)
        else:
            kind = {Sphere: "sphere", Plane: "plane", Triangle: "triangle", Mesh: "mesh"}[type(obj)]
            prims[kind] += 1
            used.add(obj.material)
            if isinstance(obj, Mesh):
                mesh_tris += len(obj.faces)

    visit(scene.root, 0)
    lights = Counter("directional" if isinstance(li, DirectionalLight) else "point"
                     for li in scene.lights)
    mirror = reflective_mask(scene.materials)
    reflective = tuple(sorted(i for i in used if mirror[i]))
    has_geometry = sum(prims.values()) > 0
    effects = {
        "-shadows": ("shadow rays from every lit point" if scene.lights and has_geometry
                     else "no effect: " + ("no lights" if not scene.lights else "no objects")),
        "-bounces": (f"mirror recursion on materials {', '.join(map(str, reflective))}"
                     if reflective else "no effect: no reflective material (|ks| > 0.1)"),
        "-jitter": ("anti-aliasing of edges and textures"
                    if has_geometry or scene.background.cube_map
                    else "no effect: constant background only"),
        "-filter": ("anti-aliasing of edges and textures"
                    if has_geometry or scene.background.cube_map
                    else "no effect: constant background only"),
    }
    return SceneInfo(
        primitives={k: prims.get(k, 0) for k in ("sphere", "plane", "triangle", "mesh")},
        mesh_triangles=mesh_tris, transforms=transforms, max_depth=max_depth,
        lights={k: lights.get(k, 0) for k in ("directional", "point")},
        materials=len(scene.materials), used_materials=tuple(sorted(used)),
        reflective_materials=reflective, cube_map=scene.background.cube_map is not None,
        ambient_forced=not scene.lights, flag_effects=effects,
    )


def format_info(scene: Scene, info: SceneInfo) -> str:
    p = info.primitives
    if info.cube_map:
        cube_map = scene.background.cube_map
        assert cube_map is not None  # info is the scene's: analyze(scene) saw its cube map
        background = "cube map " + str(cube_map.folder)
    else:
        background = "color " + " ".join(f"{c:g}" for c in scene.background.color)
    lines = [
        f"scene      {scene.path}",
        f"objects    {p['sphere']} spheres, {p['plane']} planes, {p['triangle']} triangles, "
        f"{p['mesh']} meshes ({info.mesh_triangles} triangles); {info.transforms} transforms, "
        f"nesting depth {info.max_depth}",
        f"lights     {info.lights['directional']} directional, {info.lights['point']} point"
        + ("  (none: ambient forced to 1 1 1)" if info.ambient_forced else ""),
        f"materials  {info.materials} defined, used: {list(info.used_materials)}, "
        f"reflective: {list(info.reflective_materials)}",
        "background " + background,
        "flags that can change the image:",
    ]
    lines += [f"  {flag:<9} {why}" for flag, why in info.flag_effects.items()]
    return "\n".join(lines)
