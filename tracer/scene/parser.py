"""The course scene parser (spec §1-3): text -> Scene dataclasses.

Errors are SceneError('path:line: expected X, found Y'); nothing here raises anything else for
bad input. Numbers are float32 as C's strtof gives them: too large ones become ±inf, too small
ones 0, silently (numpy's overflow warnings are off while parsing).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from . import transforms as tf
from .cubemap import load_cube_map
from .errors import SceneError, quote
from .lexer import TokenStream, iter_tokens
from .limits import (
    MAX_COUNT,
    MAX_LIGHTS,
    MAX_NESTING,
    MAX_SCENE_BYTES,
    MAX_SPHERES_PLANES,
    MAX_TRIANGLES,
    Budget,
    check_file_size,
)
from .model import (
    Background,
    Camera,
    CubeMap,
    DirectionalLight,
    Group,
    Light,
    Material,
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
from .obj import load_obj

F32 = np.float32
BLOCKS = ("PerspectiveCamera", "Lights", "Background", "Materials", "Group")
PRIMITIVES = ("Sphere", "Plane", "Triangle", "TriangleMesh")
OBJECTS = ("Group", "Transform") + PRIMITIVES
OPS = ("Translate", "Scale", "UniformScale", "XRotate", "YRotate", "ZRotate", "Rotate", "Matrix4f")


def f32(x: float) -> float:
    return float(F32(x))


def v32(v: Vec3) -> Vec3:
    return (f32(v[0]), f32(v[1]), f32(v[2]))


def normalize32(v: Vec3) -> Vec3:
    a = np.array(v, dtype=F32)
    with np.errstate(invalid="ignore", divide="ignore"):
        n = a / np.sqrt((a[0] * a[0] + a[1] * a[1]) + a[2] * a[2])
    return (float(n[0]), float(n[1]), float(n[2]))


class _Parser:
    def __init__(self, ts: TokenStream, scene_dir: Path, budget: Budget) -> None:
        self.ts = ts
        self.dir = scene_dir
        self.budget = budget
        self.material: int | None = None  # MaterialIndex is global parser state (spec §2)
        self.material_uses: list[tuple[int, int]] = []  # (index, line) checked at the end
        self.depth = 0
        self.spheres_planes = 0  # each is compiled into the render kernel: limited
        self.triangles = 0  # Triangle objects plus the faces of every TriangleMesh use
        self.meshes: dict[Path, tuple] = {}  # OBJ files already read, by path

    # --- helpers -----------------------------------------------------------------------
    def count(self, keyword: str) -> int:
        self.ts.expect(keyword)
        line = self.ts.line()
        n = self.ts.integer(keyword)
        if n < 0 or n > MAX_COUNT:
            raise self.ts.error(f"{keyword} must be in 0..{MAX_COUNT}, found {n}", line)
        return n

    def vec(self, what: str) -> Vec3:
        return v32(self.ts.vec3(what))

    def num(self, what: str) -> float:
        return f32(self.ts.number(what))

    def path_arg(self, what: str) -> tuple[Path, int]:
        tok = self.ts.next(what)
        if tok.text in ("{", "}"):
            raise self.ts.error(f"expected {what}, found {quote(tok.text)}", tok.line)
        p = Path(tok.text)
        return (p if p.is_absolute() else self.dir / p), tok.line

    # --- top level ---------------------------------------------------------------------
    def scene(self, path: Path) -> Scene:
        camera: Camera | None = None
        lights: tuple[Light, ...] = ()
        background = Background()
        materials: tuple[Material, ...] = ()
        root = Group()
        while not self.ts.at_end():
            tok = self.ts.next("a block")
            if tok.text == "PerspectiveCamera":
                camera = self.camera(tok.line)
            elif tok.text == "Lights":
                lights = self.lights()
            elif tok.text == "Background":
                background = self.background()
            elif tok.text == "Materials":
                materials = self.materials()
            elif tok.text == "Group":
                root = self.group(tok.line)
            else:
                raise self.ts.error(f"expected one of {', '.join(BLOCKS)}, found {quote(tok.text)}",
                                    tok.line)
        if camera is None:
            raise SceneError(path, None, "no PerspectiveCamera block")
        for index, line in self.material_uses:
            if index >= len(materials):
                raise self.ts.error(
                    f"MaterialIndex {index} out of range: the scene has {len(materials)} materials",
                    line)
        if not lights:
            # spec §2: a scene without lights is lit by a forced white ambient light
            background = Background(background.color, (1.0, 1.0, 1.0), background.cube_map)
        return Scene(path=path, camera=camera, lights=lights, background=background,
                     materials=materials, root=root)

    def camera(self, line: int) -> Camera:
        ts = self.ts
        ts.expect("{")
        ts.expect("center")
        center = self.vec("center")
        ts.expect("direction")
        direction = self.vec("direction")
        ts.expect("up")
        up = self.vec("up")
        ts.expect("angle")
        angle = self.num("angle")
        ts.expect("}")
        return Camera(center, direction, up, angle, line)

    def lights(self) -> tuple[Light, ...]:
        ts = self.ts
        ts.expect("{")
        line = ts.line()
        n = self.count("numLights")
        if n > MAX_LIGHTS:
            raise ts.error(f"numLights {n} is over the limit of {MAX_LIGHTS} lights (each one is "
                           "compiled into the render kernel)", line)
        out: list[Light] = []
        for _ in range(n):
            tok = ts.next("DirectionalLight or PointLight")
            if tok.text == "DirectionalLight":
                out.append(self.directional(tok.line))
            elif tok.text == "PointLight":
                out.append(self.point(tok.line))
            else:
                raise ts.error(f"expected DirectionalLight or PointLight, found {quote(tok.text)}",
                               tok.line)
        self.close_block(f"{n} lights")
        return tuple(out)

    def close_block(self, what: str) -> None:
        if not self.ts.accept("}"):
            raise self.ts.fail_expected(f"'}}' after {what}")

    def directional(self, line: int) -> DirectionalLight:
        ts = self.ts
        ts.expect("{")
        ts.expect("direction")
        d = normalize32(self.vec("direction"))
        ts.expect("color")
        c = self.vec("color")
        ts.expect("}")
        return DirectionalLight(d, c, line)

    def point(self, line: int) -> PointLight:
        ts = self.ts
        ts.expect("{")
        fields: dict = {}
        while not ts.accept("}"):
            tok = ts.next("position, color, falloff or '}'")
            if tok.text == "position":
                fields["position"] = self.vec("position")
            elif tok.text == "color":
                fields["color"] = self.vec("color")
            elif tok.text == "falloff":
                fields["falloff"] = self.num("falloff")
            else:
                raise ts.error("expected position, color, falloff or '}', "
                               f"found {quote(tok.text)}", tok.line)
        return PointLight(**fields, line=line)

    def background(self) -> Background:
        ts = self.ts
        ts.expect("{")
        color: Vec3 = (0.5, 0.5, 0.5)
        ambient: Vec3 = (0.0, 0.0, 0.0)
        cube: CubeMap | None = None
        while not ts.accept("}"):
            tok = ts.next("color, ambientLight, cubeMap or '}'")
            if tok.text == "color":
                color = self.vec("color")
            elif tok.text == "ambientLight":
                ambient = self.vec("ambientLight")
            elif tok.text == "cubeMap":
                folder, line = self.path_arg("a cube-map folder")
                cube = load_cube_map(folder, ts.path, line, self.budget)
            else:
                raise ts.error(
                    f"expected color, ambientLight, cubeMap or '}}', found {quote(tok.text)}",
                    tok.line)
        return Background(color, ambient, cube)

    def materials(self) -> tuple[Material, ...]:
        ts = self.ts
        ts.expect("{")
        n = self.count("numMaterials")
        out = []
        for _ in range(n):
            tok = ts.next("Material or PhongMaterial")
            if tok.text not in ("Material", "PhongMaterial"):
                raise ts.error(f"expected Material or PhongMaterial, found {quote(tok.text)}",
                               tok.line)
            out.append(self.material_block(tok.line))
        self.close_block(f"{n} materials")
        return tuple(out)

    def material_block(self, line: int) -> Material:
        ts = self.ts
        ts.expect("{")
        fields: dict = {}
        while not ts.accept("}"):
            tok = ts.next("a material field or '}'")
            if tok.text == "diffuseColor":
                fields["diffuse"] = self.vec("diffuseColor")
            elif tok.text == "specularColor":
                fields["specular"] = self.vec("specularColor")
            elif tok.text == "shininess":
                fields["shininess"] = self.num("shininess")
            elif tok.text == "bump":
                ts.next("a bump map token")  # read and ignored, as the reference does
            else:
                raise ts.error(
                    "expected diffuseColor, specularColor, shininess, bump or '}', "
                    f"found {quote(tok.text)}", tok.line)
        return Material(**fields, line=line)

    # --- objects -----------------------------------------------------------------------
    def enter(self, line: int) -> None:
        self.depth += 1
        if self.depth > MAX_NESTING:
            raise self.ts.error(f"objects nested deeper than {MAX_NESTING} levels", line)

    def group(self, line: int) -> Group:
        ts = self.ts
        self.enter(line)
        ts.expect("{")
        n = self.count("numObjects")
        objects: list[SceneObject] = []
        while True:
            tok = ts.peek()
            if tok is not None and tok.text == "MaterialIndex":
                self.material_index()
                continue
            if len(objects) == n:
                break
            objects.append(self.object(f"an object ({len(objects)} of {n} read)"))
        self.close_block(f"{n} objects")
        self.depth -= 1
        return Group(tuple(objects), line)

    def material_index(self) -> None:
        ts = self.ts
        ts.expect("MaterialIndex")
        line = ts.line()
        k = ts.integer("MaterialIndex")
        if k < 0:
            raise ts.error(f"MaterialIndex must be 0 or more, found {k}", line)
        self.material = k
        self.material_uses.append((k, line))

    def current_material(self, kind: str, line: int) -> int:
        if self.material is None:
            raise self.ts.error(f"{kind} before any MaterialIndex", line)
        return self.material

    def object(self, what: str) -> SceneObject:
        ts = self.ts
        tok = ts.next(what)
        kind, line = tok.text, tok.line
        if kind == "Group":
            return self.group(line)
        if kind == "Transform":
            return self.transform(line)
        if kind not in PRIMITIVES:
            raise ts.error(f"expected {what}: one of {', '.join(OBJECTS)}, found {quote(kind)}",
                           line)
        material = self.current_material(kind, line)
        if kind in ("Sphere", "Plane"):
            self.spheres_planes += 1
            if self.spheres_planes > MAX_SPHERES_PLANES:
                raise ts.error(f"more than {MAX_SPHERES_PLANES} spheres and planes (each one is "
                               "compiled into the render kernel; use a TriangleMesh)", line)
        ts.expect("{")
        if kind == "Sphere":
            ts.expect("center")
            c = self.vec("center")
            ts.expect("radius")
            obj: SceneObject = Sphere(c, self.num("radius"), material, line)
        elif kind == "Plane":
            ts.expect("normal")
            n = self.vec("normal")
            ts.expect("offset")
            obj = Plane(n, self.num("offset"), material, line)
        elif kind == "Triangle":
            vs = []
            for name in ("vertex0", "vertex1", "vertex2"):
                ts.expect(name)
                vs.append(self.vec(name))
            obj = Triangle(vs[0], vs[1], vs[2], material, line)
            self.add_triangles(1, line)
        else:
            ts.expect("obj_file")
            path, pline = self.path_arg("an OBJ file name")
            if path not in self.meshes:
                self.meshes[path] = load_obj(path, ts.path, pline, self.budget)
            v, f, n = self.meshes[path]
            self.add_triangles(len(f), pline)
            obj = Mesh(path, v, f, n, material, line)
        ts.expect("}")
        return obj

    def add_triangles(self, count: int, line: int) -> None:
        self.triangles += count
        if self.triangles > MAX_TRIANGLES:
            raise self.ts.error(f"more than {MAX_TRIANGLES} triangles in the scene "
                                "(every TriangleMesh use counts its faces)", line)

    def transform(self, line: int) -> Transform:
        ts = self.ts
        self.enter(line)
        ts.expect("{")
        m = np.eye(4, dtype=F32)
        while True:
            tok = ts.peek()
            if tok is None or tok.text not in OPS:
                break
            ts.next("a transform op")
            op = tok.text
            if op == "Matrix4f":
                ts.expect("{")
                vals = [self.num("Matrix4f") for _ in range(16)]
                ts.expect("}")
                m = tf.product(tf.from_columns(vals), m)  # Matrix4f left-multiplies (spec §2)
                continue
            if op == "Translate":
                opm = tf.translate(*self.vec("Translate"))
            elif op == "Scale":
                opm = tf.scale(*self.vec("Scale"))
            elif op == "UniformScale":
                s = self.num("UniformScale")
                opm = tf.scale(s, s, s)
            elif op == "Rotate":
                ts.expect("{")
                ax, ay, az = self.vec("Rotate axis")
                deg = self.num("Rotate angle")
                ts.expect("}")
                opm = tf.rotate(ax, ay, az, deg)
            else:
                opm = tf.rotate_axis("XYZ".index(op[0]), self.num(op))
            m = tf.product(m, opm)  # every other op right-multiplies: the first listed applies last
        if (following := ts.peek()) is not None and following.text == "}":
            raise ts.fail_expected("a transform op or one object")
        child = self.object("a transform op or one object")
        ts.expect("}")
        self.depth -= 1
        return Transform(m.astype(F32), child, line)


def parse_scene_text(text: str, path: Path, budget: Budget = Budget()) -> Scene:
    last_line = text.count("\n") + 1
    ts = TokenStream(iter_tokens(text), path, last_line)
    # IEEE float32 semantics: 1e39 -> inf, inf * 0 -> NaN, ... without numpy warnings.
    with np.errstate(all="ignore"):
        return _Parser(ts, path.parent, budget).scene(path)


def load_scene(path: Path | str, budget: Budget = Budget()) -> Scene:
    """Parse a course scene file. Raises SceneError for any problem with it or its files,
    meshes and cube-map faces too large for the memory budget included (from their sizes,
    before they are decoded)."""
    path = Path(path)
    if path.suffix != ".txt":
        raise SceneError(path, None, "a scene file name must end in .txt")
    if not path.is_file():
        raise SceneError(path, None, "scene file not found")
    check_file_size(path, MAX_SCENE_BYTES, path, None)
    try:
        raw = path.read_bytes()
    except OSError as e:
        raise SceneError(path, None, f"cannot read scene file: {e.strerror}") from None
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as e:
        line = raw[: e.start].count(b"\n") + 1
        raise SceneError(path, line, "scene file is not text (invalid UTF-8)") from None
    return parse_scene_text(text, path, budget)
