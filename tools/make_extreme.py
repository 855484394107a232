#!/usr/bin/env python3
"""Generate the offset/scale family of scenes/extreme/: one scene, moved far from the origin or
shrunk, to show float32's precision limits (shadow acne, light leaks).

    .venv/bin/python tools/make_extreme.py [--out DIR]

Writes offset_0.txt (the reference), offset_1e3.txt, offset_1e5.txt, offset_1e7.txt (every
position moved by (t, t, t)) and scale_1e-3.txt (every length times 1e-3, point-light falloff
times 1e6 so that the lighting is the same). Numbers are written with 12 significant digits,
so the files are the same on every run; the parser rounds them to float32, which is the point.
"""
from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

OUT = Path(__file__).resolve().parent.parent / "scenes" / "extreme"

# The base scene, in its own units: a floor, a sphere resting on it, a mirror sphere, a box
# (a transformed mesh) and a leaning triangle, under a point light and a directional light.
CAMERA: dict[str, Any] = dict(center=(0.0, 2.5, 8.0), direction=(0.0, -0.3, -1.0),
                              up=(0.0, 1.0, -0.3), angle=40)
POINT: dict[str, Any] = dict(position=(2.0, 5.0, 4.0), color=(0.9, 0.85, 0.8), falloff=0.04)
DIRECTIONAL: dict[str, Any] = dict(direction=(-0.4, -1.0, -0.3), color=(0.3, 0.3, 0.35))
FLOOR_Y = 0.0
SPHERES = [((-1.2, 1.0, 0.0), 1.0, 1), ((1.4, 0.6, 0.6), 0.6, 2)]
BOX: dict[str, Any] = dict(translate=(0.4, 0.5, 2.0), yrotate=25, scale=0.5)
TRIANGLE = ((-3.0, 0.0, -1.0), (-1.5, 0.0, -2.5), (-2.6, 2.2, -2.0))
DEPTH = (5.0, 12.0)

FAMILY = {
    # name: (offset t, scale s, what it probes)
    "offset_0": (0.0, 1.0, "The reference of the offset/scale family (tools/make_extreme.py): a "
                 "floor, a sphere resting on it, a mirror sphere, a box mesh and a leaning "
                 "triangle under a point and a directional light, near the origin."),
    "offset_1e3": (1e3, 1.0, "offset_0 with every position moved by (1e3, 1e3, 1e3): float32 "
                   "spacing there is 6e-5, far below the 0.01 shadow offset: should look like "
                   "offset_0."),
    "offset_1e5": (1e5, 1.0, "offset_0 moved by (1e5, 1e5, 1e5): float32 spacing is 0.0078, "
                   "close to the 0.01 shadow/reflection offset: hit points land below the "
                   "surface, so shadow acne and speckled reflections appear."),
    "offset_1e7": (1e7, 1.0, "offset_0 moved by (1e7, 1e7, 1e7): float32 spacing is 1 unit, as "
                   "large as the objects: positions snap to whole units, the geometry and "
                   "shading fall apart (course arithmetic, not a bug)."),
    "scale_1e-3": (0.0, 1e-3, "offset_0 shrunk to 1e-3 units (falloff times 1e6, so the light "
                   "is the same): the fixed 0.01 shadow and reflection offsets are worth 10 "
                   "units of offset_0, longer than the scene, so shadows vanish (light leaks) "
                   "and the mirror skips nearby objects."),
}


def fmt(x: float) -> str:
    text = f"{x:.12g}"
    return "0" if text == "-0" else text


def vec(v) -> str:
    return " ".join(fmt(c) for c in v)


def scene_text(t: float, s: float, description: str) -> str:
    def pos(p):  # a position: scaled, then moved
        return tuple(c * s + t for c in p)

    lo, hi = DEPTH[0] * s, DEPTH[1] * s
    out = [f"# {description}",
           f"# flags: -shadows -bounces 2 -depth {fmt(lo)} {fmt(hi)}",
           "PerspectiveCamera {",
           f"    center {vec(pos(CAMERA['center']))}",
           f"    direction {vec(CAMERA['direction'])}",
           f"    up {vec(CAMERA['up'])}",
           f"    angle {CAMERA['angle']}",
           "}",
           "",
           "Lights {",
           "    numLights 2",
           f"    PointLight {{ position {vec(pos(POINT['position']))} color {vec(POINT['color'])} "
           f"falloff {fmt(POINT['falloff'] / (s * s))} }}",
           f"    DirectionalLight {{ direction {vec(DIRECTIONAL['direction'])} "
           f"color {vec(DIRECTIONAL['color'])} }}",
           "}",
           "",
           "Background {",
           "    color 0.15 0.2 0.3",
           "    ambientLight 0.1 0.1 0.1",
           "}",
           "",
           "Materials {",
           "    numMaterials 5",
           "    Material { diffuseColor 0.8 0.8 0.8 }",
           "    Material { diffuseColor 0.9 0.3 0.2 specularColor 0.3 0.3 0.3 shininess 20 }",
           "    Material { diffuseColor 0.1 0.1 0.1 specularColor 0.8 0.8 0.8 shininess 50 }",
           "    Material { diffuseColor 0.2 0.5 0.9 }",
           "    Material { diffuseColor 0.9 0.8 0.2 }",
           "}",
           "",
           "Group {",
           "    numObjects 5",
           "    MaterialIndex 0",
           f"    Plane {{ normal 0 1 0 offset {fmt(FLOOR_Y * s + t)} }}"]
    for center, radius, material in SPHERES:
        out += [f"    MaterialIndex {material}",
                f"    Sphere {{ center {vec(pos(center))} radius {fmt(radius * s)} }}"]
    out += ["    MaterialIndex 3",
            "    Transform {",
            f"        Translate {vec(pos(BOX['translate']))}",
            f"        YRotate {BOX['yrotate']}",
            f"        UniformScale {fmt(BOX['scale'] * s)}",
            "        TriangleMesh { obj_file ../assets/cube_flat.obj }",
            "    }",
            "    MaterialIndex 4",
            f"    Triangle {{ vertex0 {vec(pos(TRIANGLE[0]))} vertex1 {vec(pos(TRIANGLE[1]))} "
            f"vertex2 {vec(pos(TRIANGLE[2]))} }}",
            "}",
            ""]
    return "\n".join(out)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=OUT)
    args = ap.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    for name, (t, s, description) in FAMILY.items():
        (args.out / f"{name}.txt").write_text(scene_text(t, s, description), encoding="utf-8")


if __name__ == "__main__":
    main()
