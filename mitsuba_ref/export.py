"""Mitsuba XML export of a course scene: `raycheck export SCENE -o scene.xml [course flags]`.

The XML is written from the same plan as the `mi.load_dict` scene (translate.plan), so it holds
the same plugins and renders the same image once `mitsuba_ref` is imported (which registers
course_camera, course_phong and course_whitted):

    import raycheck.mitsuba_ref, mitsuba as mi
    image = mi.render(mi.load_file("scene.xml"))   # R, G, B (+ nx, ny, nz, depth) channels

Meshes go to binary PLY files in `<name>_meshes/` beside the XML. Mitsuba's `ply` loader
renormalizes every vertex normal after applying `to_world`, which is exact for the course only
when the transform is a similarity or the mesh is flat-shaded (unshared vertices); any other
transformed mesh is written in object space inside a `shapegroup` with a transformed
`instance`, so the normal is normalize(M^-T normalize(Σ b_i n_i)) exactly as in the course.

Two things the XML cannot say: the 1-2-1 kernel of `-filter` (the XML renders the 3w x 3h
sub-pixel film; mitsuba_ref.render.filter_121 reduces it) and the split of very large jittered
renders into passes.
"""
from __future__ import annotations

import math
import os
import shutil
import sys
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path
from typing import Any, cast
from xml.sax.saxutils import quoteattr

import numpy as np

from raycheck.tracer.process import run_command
from raycheck.tracer.scene import SceneError, load_scene
from raycheck.tracer.scene.flags import (
    FLAG_ARITY,
    FlagError,
    check_output_path,
    parse_course_flags,
    wants_help,
)
from raycheck.tracer.scene.model import Scene
from raycheck.tracer.scene.outputs import write_all
from raycheck.tracer.scene.request import request_fields

from . import translate

# plugin type -> XML tag
TAGS = {
    "sphere": "shape", "disk": "shape", "instance": "shape", "shapegroup": "shape",
    "ply": "shape", "course_phong": "bsdf", "point": "emitter", "directional": "emitter",
    "course_camera": "sensor", "hdrfilm": "film", "box": "rfilter", "independent": "sampler",
    "stratified": "sampler", "course_whitted": "integrator",
}
POINTS = {"center", "position"}        # 3-vectors written as <point>
USAGE = ("usage: {prog} SCENE.txt -o scene.xml [-size w h] [-bounces n] [-shadows] [-jitter] "
         "[-filter] [-output a.png] [-normals n.png] [-depth min max d.png]")
EXPORT_HELP = ("Write a course scene as a Mitsuba XML file (meshes as PLY files in "
               "<name>_meshes/ beside it; the cube map by a path relative to it), rendering "
               "what `raycheck reference` renders once mitsuba_ref is imported.\n\n"
               "  SCENE.txt (or -input SCENE.txt)  the course scene\n"
               "  -o, --output scene.xml           the XML file to write\n"
               "  course flags                     the film size, integrator settings and "
               "AOVs: -output/-normals/-depth\n"
               "                                   only say which images the XML renders\n"
               "  -h, --help                       this help")


def _num(x: float) -> str:
    """Shortest text that reads back as the same float32 (Mitsuba parses into float32)."""
    x = float(x)
    if math.isnan(x):
        return "nan"
    if math.isinf(x):
        return "inf" if x > 0 else "-inf"
    with np.errstate(over="ignore"):
        return str(np.float32(x))


def write_ply(path: Path, vertices: np.ndarray, faces: np.ndarray, normals: np.ndarray) -> None:
    """Binary little-endian PLY with float32 positions and normals, int32 triangle indices."""
    v = np.ascontiguousarray(np.hstack([vertices, normals]).astype("<f4"))
    f = np.empty(len(faces), dtype=[("n", "u1"), ("i", "<i4", 3)])
    f["n"] = 3
    f["i"] = faces
    header = ("ply\nformat binary_little_endian 1.0\n"
              f"element vertex {len(v)}\n"
              "property float x\nproperty float y\nproperty float z\n"
              "property float nx\nproperty float ny\nproperty float nz\n"
              f"element face {len(f)}\n"
              "property list uchar int vertex_indices\nend_header\n")
    with open(path, "wb") as out:
        out.write(header.encode("ascii"))
        out.write(v.tobytes())
        out.write(f.tobytes())


class _XmlWriter:
    def __init__(self, xml_path: Path, mesh_dir: Path) -> None:
        self.xml_path = xml_path
        self.mesh_dir = mesh_dir
        self.lines: list[str] = []
        self.meshes: list[tuple[Path, translate.MeshData]] = []  # written in object space
        self.groups = 0

    def emit(self, depth: int, text: str) -> None:
        self.lines.append("    " * depth + text)

    def matrix(self, depth: int, m: np.ndarray) -> None:
        values = ", ".join(_num(x) for x in np.asarray(m, dtype=np.float64).reshape(-1))
        self.emit(depth, '<transform name="to_world">')
        self.emit(depth + 1, f'<matrix value="{values}"/>')
        self.emit(depth, "</transform>")

    def value(self, depth: int, name: str, v: Any) -> None:
        n = quoteattr(name)
        if isinstance(v, dict) and v.get("type") == "ref":
            self.emit(depth, f'<ref name={n} id={quoteattr(v["id"])}/>')
        elif isinstance(v, dict) and v.get("type") == "rgb":
            self.emit(depth, f'<rgb name={n} value="{", ".join(_num(x) for x in v["value"])}"/>')
        elif isinstance(v, dict) and v.get("type") == "mesh":
            raise TypeError("meshes are written as shapes")  # pragma: no cover
        elif isinstance(v, dict):
            self.plugin(depth, v, name=name)
        elif name == "to_world":
            self.matrix(depth, v)
        elif isinstance(v, bool):
            self.emit(depth, f'<boolean name={n} value="{str(v).lower()}"/>')
        elif isinstance(v, int):
            self.emit(depth, f'<integer name={n} value="{v}"/>')
        elif isinstance(v, float):
            self.emit(depth, f'<float name={n} value="{_num(v)}"/>')
        elif isinstance(v, str):
            if name == "cube_map":  # relative to the XML, which Mitsuba's resolver searches
                v = os.path.relpath(v, self.xml_path.parent.resolve())
            self.emit(depth, f'<string name={n} value={quoteattr(v)}/>')
        elif isinstance(v, (list, tuple)) and len(v) == 3:
            tag = "point" if name in POINTS else "vector"
            x, y, z = (_num(c) for c in v)
            self.emit(depth, f'<{tag} name={n} x="{x}" y="{y}" z="{z}"/>')
        else:  # pragma: no cover - the plan holds nothing else
            raise TypeError(f"cannot write {name}={v!r} to XML")

    def plugin(self, depth: int, d: dict[str, Any], name: str | None = None,
               ident: str | None = None) -> None:
        kind = d["type"]
        if kind == "mesh":
            self.mesh(depth, d, ident)
            return
        attrs = f' type="{kind}"'
        if ident is not None:
            attrs += f" id={quoteattr(ident)}"
        elif name is not None and TAGS[kind] not in ("film", "rfilter", "sampler"):
            attrs += f" name={quoteattr(name)}"
        children = [(key, v) for key, v in d.items() if key != "type"]
        if not children:
            self.emit(depth, f"<{TAGS[kind]}{attrs}/>")
            return
        self.emit(depth, f"<{TAGS[kind]}{attrs}>")
        for key, v in children:
            self.value(depth + 1, key, v)
        self.emit(depth, f"</{TAGS[kind]}>")

    def mesh(self, depth: int, d: dict[str, Any], ident: str | None) -> None:
        data: translate.MeshData = d["data"]
        ply = self.mesh_dir / f"{data.name}.ply"
        rel = os.path.relpath(ply, self.xml_path.parent)
        m = data.matrix
        if m is None or data.flat or translate.similarity_scale(m) is not None:
            # in world space, moved on the host as the load_dict form does (float64, then
            # float32): Mitsuba's own to_world would round the vertices differently
            v, n = data.world()
            self.meshes.append((ply, replace(data, vertices=v, normals=n, matrix=None)))
            body = {"type": "ply", "filename": rel, "bsdf": d["bsdf"]}
            self.plugin(depth, body, ident=ident)
            return
        # smooth mesh under a non-similarity: object space in a shapegroup, plus an instance
        self.meshes.append((ply, data))
        group = f"meshgroup_{self.groups:03d}"
        self.groups += 1
        self.plugin(depth, {"type": "shapegroup",
                            "mesh": {"type": "ply", "filename": rel, "bsdf": d["bsdf"]}},
                    ident=group)
        self.plugin(depth, {"type": "instance", "shapegroup": {"type": "ref", "id": group},
                            "to_world": m}, ident=ident)


def xml_text(plan: dict[str, Any], xml_path: Path, mesh_dir: Path
             ) -> tuple[str, list[tuple[Path, translate.MeshData]]]:
    w = _XmlWriter(xml_path, mesh_dir)
    w.emit(0, '<scene version="3.0.0">')
    w.emit(1, "<!-- written by raycheck export; load after `import raycheck.mitsuba_ref` -->")
    for key, v in plan.items():
        if key == "type":
            continue
        w.plugin(1, v, ident=key)
    w.emit(0, "</scene>")
    return "\n".join(w.lines) + "\n", w.meshes


def write_xml(scene: Scene, path: Path, settings: translate.Settings | None = None) -> list[Path]:
    """Write the Mitsuba XML for `scene` and its PLY meshes, all or nothing (a failed write
    leaves no mesh and no XML, and no mesh folder it made); returns the files written."""
    path = Path(path)
    settings = settings or translate.Settings()
    plan = translate.plan(scene, settings)
    mesh_dir = path.parent / f"{path.stem}_meshes"
    text, meshes = xml_text(plan, path, mesh_dir)
    made_dir = bool(meshes) and not mesh_dir.is_dir()
    if made_dir:
        mesh_dir.mkdir()
    # write_all's writer type: mypy cannot match a lambda with a default argument to it, and
    # it ignores the text writer's return value (the number of characters written)
    files = [(ply, cast("Callable[[str], None]",
                        lambda tmp, d=data: write_ply(Path(tmp), d.vertices, d.faces, d.normals)))
             for ply, data in meshes]
    files.append((path, cast("Callable[[str], None]",
                             lambda tmp: Path(tmp).write_text(text, encoding="utf-8"))))
    try:
        write_all(files)
    except BaseException:
        if made_dir:
            shutil.rmtree(mesh_dir, ignore_errors=True)
        raise
    return [f for f, _ in files]


def settings_from_args(argv: list[str]) -> tuple[Path, Path, translate.Settings]:
    """SCENE -o scene.xml plus course flags (their values are skipped when looking for SCENE);
    -output/-normals/-depth only say which images the XML's integrator produces."""
    scene_path = None
    output = None
    rest: list[str] = []
    i = 0
    while i < len(argv):
        a = argv[i]
        if a in ("-o", "--output"):
            if i + 1 >= len(argv):
                raise FlagError(f"{a} needs a file name")
            output = Path(argv[i + 1])
            i += 2
        elif a in FLAG_ARITY:
            n = FLAG_ARITY[a]
            rest += argv[i:i + 1 + n]
            i += 1 + n
        elif not a.startswith("-") and scene_path is None:
            scene_path = a
            i += 1
        else:
            rest.append(a)
            i += 1
    if scene_path is not None:
        if "-input" in rest:
            raise FlagError(f"two scenes: {scene_path} and -input "
                            f"{rest[rest.index('-input') + 1]}; give one")
        rest = ["-input", scene_path] + rest
    cmd = parse_course_flags(rest)
    if output is None:
        raise FlagError("-o scene.xml is required")
    check_output_path(output, ".xml")
    # the XML always renders the color; -normals and -depth add their AOVs
    fields = request_fields(cmd.request) | {"kinds": ("color", *cmd.request.kinds)}
    settings = translate.Settings(**fields)
    problem = settings.limit_problem()  # the same request limits as a render
    if problem:
        raise FlagError(problem)
    assert cmd.input is not None  # parse_course_flags requires -input unless told otherwise
    return cmd.input, output, settings


def main_export(argv: list[str] | None = None, prog: str = "raycheck export") -> int:
    argv = sys.argv[1:] if argv is None else [str(a) for a in argv]
    if not argv:
        print(USAGE.format(prog=prog), file=sys.stderr)
        return 2
    if wants_help(argv):
        print(USAGE.format(prog=prog) + "\n\n" + EXPORT_HELP)
        return 0

    def export() -> int:
        scene_path, output, settings = settings_from_args(argv)
        scene = load_scene(scene_path)
        for written in write_xml(scene, output, settings):
            print(written)
        return 0

    return run_command(prog, export, (FlagError, SceneError))


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main_export())
