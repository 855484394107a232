"""Fuzzing the scene parser, the OBJ and cube-map loaders and the command line with hypothesis.

Inputs are mutations of the bundled scenes (dropped, duplicated, swapped and replaced tokens,
hostile numbers, random bytes, generated deep nesting), random OBJ text, damaged PNG faces and
random flag lists. The property everywhere: a clear one-line error naming the file (and line)
or a correct result; never another exception, a warning, a hang or a partial output file.

Every test is derandomized and bounded (settings below), so CI runs the same inputs each time
in well under a minute on two cores; the quick run (without CI=true) tries a fifth as many.
Set RAYCHECK_FUZZ_SCALE=N to try N times as many inputs (e.g. for a longer local campaign);
`pytest --hypothesis-show-statistics` prints the counts.
"""
from __future__ import annotations

import io
import os
import re
import tempfile
import warnings
import zlib
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st

from raycheck.tracer.cli import EXTRA_OPTIONS
from raycheck.tracer.cli import main as tracer_main
from raycheck.tracer.image import read_png
from raycheck.tracer.options import RenderOptions
from raycheck.tracer.render import Renderer
from raycheck.tracer.scene import Scene, SceneError, load_scene, parse_scene_text
from raycheck.tracer.scene.errors import printable
from raycheck.tracer.scene.flags import parse_course_flags
from raycheck.tracer.scene.lexer import tokenize
from raycheck.tracer.scene.limits import MAX_NESTING
from raycheck.tracer.scene.obj import parse_obj

REPO = Path(__file__).resolve().parents[2]
SCENE_FILES = sorted((REPO / "scenes" / "course").glob("*.txt")) + \
    sorted((REPO / "scenes" / "features").glob("*.txt"))
CORPUS = {p: p.read_text(encoding="utf-8") for p in SCENE_FILES}
SKY = REPO / "scenes" / "assets" / "sky"

SCALE = max(1, int(os.environ.get("RAYCHECK_FUZZ_SCALE", "1")))
# Outside CI (tests/conftest.py's rule for the full matrix) a fifth of the inputs: the fuzz
# tests were a sixth of the quick suite's time; CI (CI=true) tries them all.
QUICK_SHARE = 1 if os.environ.get("CI") == "true" else 5


PROGRESS = re.compile(r"rendering: +\d+% after \d+\.\d s")  # tracer/cli.py's Progress
PARSE_DEADLINE_MS = 10_000  # parsing one input takes milliseconds: far over this is a hang


def fuzz_settings(n: int, deadline: int | None = None) -> settings:
    return settings(max_examples=max(1, n * SCALE // QUICK_SHARE), deadline=deadline,
                    derandomize=True, database=None,
                    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large,
                                           HealthCheck.function_scoped_fixture])


# --- token material -------------------------------------------------------------------------
KEYWORDS = sorted({t.text for text in CORPUS.values() for t in tokenize(text)
                   if not re.fullmatch(r"[-+.0-9eE]+", t.text)})
HOSTILE_NUMBERS = [
    "1e39", "-1e39", "3.4028235e38", "3.5e38", "1e-50", "-1e-50", "1e-45", "1e308", "1e309",
    "1e99999", "-0", "0", "nan", "NaN", "inf", "-inf", "Infinity", "0x10", "1.2.3", "1e", "1e+",
    "e5", ".", "-", "+", "--1", "+-1", "1..2", "9" * 400, "9" * 5000, "0." + "0" * 300 + "1",
    "1" + "0" * 40, "\u0663", "\uff11", "1\u00a02", "1,5", "2.5}", "1}}}", "-.16}", "1.}",
    "99999999999", "-99999999999", "4294967296", "18446744073709551617",
]
HOSTILE_TOKENS = HOSTILE_NUMBERS + [
    "{", "}", "{}", "}{", "#", "#}", "\x00", "\x1b[31m", "\u2028", "\ufeff", "\r", "\x0b",
    "Group", "Transform", "MaterialIndex", "numObjects", "Sphere", "obj_file", "cubeMap",
    "missing.obj", "../assets", "/dev/zero", "/", "", "x" * 2000,
]

hostile_token = st.one_of(st.sampled_from(HOSTILE_TOKENS), st.sampled_from(KEYWORDS),
                          st.text(max_size=12),
                          st.integers(-10**20, 10**20).map(str),
                          st.floats(allow_nan=False, allow_infinity=False).map(repr))


@st.composite
def mutated_scene(draw) -> tuple[Path, str]:
    """A bundled scene with 1-6 token mutations. Separators (whitespace runs, line breaks)
    are kept, so line numbers stay meaningful."""
    path = draw(st.sampled_from(SCENE_FILES))
    parts = re.split(r"(\s+)", CORPUS[path])  # words at even indices
    words = parts[0::2]
    seps = parts[1::2]
    for _ in range(draw(st.integers(1, 6))):
        if not words:
            break
        op = draw(st.sampled_from(["drop", "dup", "swap", "replace", "insert", "number"]))
        i = draw(st.integers(0, len(words) - 1))
        if op == "drop":
            words[i] = ""
        elif op == "dup":
            words[i] = words[i] + " " + words[i]
        elif op == "swap":
            j = draw(st.integers(0, len(words) - 1))
            words[i], words[j] = words[j], words[i]
        elif op == "replace":
            words[i] = draw(hostile_token)
        elif op == "insert":
            words[i] = draw(hostile_token) + " " + words[i]
        else:  # replace a number by a hostile one
            nums = [k for k, w in enumerate(words) if re.fullmatch(r"[-+.0-9eE]+}*", w)]
            if nums:
                words[draw(st.sampled_from(nums))] = draw(st.sampled_from(HOSTILE_NUMBERS))
    out = []
    for k, w in enumerate(words):
        out.append(w)
        if k < len(seps):
            out.append(seps[k])
    return path, "".join(out)


def check_error(e: SceneError, known_paths: list[Path], text_by_path: dict | None = None) -> None:
    """The message is one printable line 'path: ...' or 'path:line: ...' with a known path and,
    for a scene file, a line number inside it."""
    msg = str(e)
    assert "\n" not in msg and msg.isprintable(), repr(msg)
    assert any(msg.startswith(f"{p}:") for p in known_paths), msg
    if e.line is not None:
        assert e.line >= 1
        if text_by_path and e.path in text_by_path:
            assert e.line <= text_by_path[e.path].count("\n") + 1, msg
    assert msg == printable((f"{e.path}:{e.line}: " if e.line else f"{e.path}: ") + e.message)


def parse_checked(text: str, path: Path, extra_paths: list[Path] = ()) -> Scene | None:
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # a numpy overflow warning would reach the user's stderr
        try:
            scene = parse_scene_text(text, path)
        except SceneError as e:
            check_error(e, [path, *extra_paths], {path: text})
            event("SceneError")
            return None
    assert isinstance(scene, Scene)
    event("Scene")
    return scene


# --- the scene parser ----------------------------------------------------------------------
@fuzz_settings(3000, PARSE_DEADLINE_MS)
@given(mutated_scene())
def test_mutated_bundled_scenes_parse_or_fail_cleanly(case):
    path, text = case
    parse_checked(text, path)


@fuzz_settings(300, PARSE_DEADLINE_MS)
@given(st.binary(max_size=600))
def test_random_bytes_load_or_fail_cleanly(data):
    with tempfile.TemporaryDirectory() as d:
        p = Path(d) / "s.txt"
        p.write_bytes(data)
        try:
            load_scene(p)
            event("Scene")
        except SceneError as e:
            check_error(e, [p])
            event("SceneError")


@fuzz_settings(300, PARSE_DEADLINE_MS)
@given(st.lists(st.sampled_from(
    ["{", "}", " ", " ", " ", "\n", "Group", "Transform", "numObjects", "1", "0", "-1",
     "MaterialIndex", "Sphere", "center", "radius", "Translate", "UniformScale", "2", "Materials",
     "Material", "numMaterials", "PerspectiveCamera", "Lights", "numLights", "PointLight", "#",
     "1e39", "\x00", "\u2028", "\r"]), max_size=200).map("".join))
def test_random_keyword_soup(text):
    cam = "PerspectiveCamera { center 0 0 10 direction 0 0 -1 up 0 1 0 angle 30 }\n"
    parse_checked(cam + text, Path("/fuzz/soup.txt"))


@fuzz_settings(100, PARSE_DEADLINE_MS)
@given(depth=st.integers(0, 3 * MAX_NESTING), kinds=st.lists(st.sampled_from(
    ["Group", "Transform", "TransformOps"]), min_size=1, max_size=3),
    close=st.integers(-2, 2))
def test_generated_deep_nesting(depth, kinds, close):
    """Nested Groups and Transforms up to three times the limit, with missing or extra braces:
    over the limit is a one-line error at the first level too deep, never a RecursionError."""
    head = ("PerspectiveCamera { center 0 0 10 direction 0 0 -1 up 0 1 0 angle 30 }\n"
            "Materials { numMaterials 1 Material { } }\nGroup { numObjects 1 MaterialIndex 0\n")
    opens = []
    for k in range(depth):
        kind = kinds[k % len(kinds)]
        if kind == "Group":
            opens.append("Group { numObjects 1\n")
        elif kind == "Transform":
            opens.append("Transform {\n")
        else:
            opens.append("Transform { Translate 1 0 0 Rotate { 0 1 0 90 } Matrix4f { "
                         + " ".join(["1"] * 16) + " }\n")
    body = "Sphere { center 0 0 0 radius 1 }\n"
    text = head + "".join(opens) + body + "}\n" * max(0, depth + 1 + close)
    scene = parse_checked(text, Path("/fuzz/deep.txt"))
    if depth + 1 > MAX_NESTING:
        assert scene is None
    elif close == 0:
        assert scene is not None


# --- OBJ files -----------------------------------------------------------------------------
obj_number = st.one_of(st.sampled_from(HOSTILE_NUMBERS[:20] + ["1", "0", "-1", "0.5"]),
                       st.floats(-1e3, 1e3).map(lambda x: f"{x:g}"))
obj_index = st.one_of(st.integers(-3, 6).map(str),
                      st.sampled_from(["99999999999999999999", "9" * 5000, "1.5", "a", "",
                                       "1/1", "2//3", "3/4/5", "/1", "+1", "0x1", "\u0663"]))
obj_line = st.one_of(
    st.tuples(st.just("v"), st.lists(obj_number, min_size=0, max_size=5)).map(
        lambda t: " ".join([t[0], *t[1]])),
    st.tuples(st.just("f"), st.lists(obj_index, min_size=0, max_size=5)).map(
        lambda t: " ".join([t[0], *t[1]])),
    st.sampled_from(["vt 0 0", "vn 0 0 1", "# comment", "", "v", "f", "o x", "g", "s off",
                     "usemtl a", "mtllib x.mtl", "\r", "v 0 0 0\r", "f 1 2 3\r", "\x00\x00\x00"]),
    st.text(max_size=20),
)
VALID_TRIANGLE = ["v 0 0 0", "v 1 0 0", "v 0 1 0", "f 1 2 3"]


@fuzz_settings(600, PARSE_DEADLINE_MS)
@given(lines=st.lists(obj_line, max_size=12), prefix_valid=st.booleans())
def test_random_obj_files(lines, prefix_valid):
    text = "\n".join((VALID_TRIANGLE if prefix_valid else []) + lines)
    with tempfile.TemporaryDirectory() as d:
        obj = Path(d) / "m.obj"
        obj.write_text(text, encoding="utf-8", errors="surrogatepass")
        scene_path = Path(d) / "s.txt"
        scene_text = ("PerspectiveCamera { center 0 0 10 direction 0 0 -1 up 0 1 0 angle 30 }\n"
                      "Materials { numMaterials 1 Material { } }\n"
                      "Group { numObjects 2 MaterialIndex 0\n"
                      "  TriangleMesh { obj_file m.obj }\n"
                      "  Transform { Scale 1 2 3 TriangleMesh { obj_file m.obj } } }\n")
        scene = parse_checked(scene_text, scene_path, [obj])
        if scene is not None:
            mesh = scene.root.objects[0]
            assert len(mesh.faces) > 0
            assert mesh.faces.min() >= 0 and mesh.faces.max() < len(mesh.vertices)
            assert mesh.normals.shape == mesh.vertices.shape
            with warnings.catch_warnings():
                warnings.simplefilter("error")
                try:
                    parse_obj(text, obj)
                except SceneError as e:
                    raise AssertionError(f"the mesh parsed in the scene but not alone: {e}")


# --- cube maps -----------------------------------------------------------------------------
def png_bytes(mode: str, size: tuple[int, int], seed: int) -> bytes:
    from PIL import Image

    rng = np.random.default_rng(seed)
    w, h = size
    if mode == "I;16":
        im = Image.fromarray(rng.integers(0, 65536, (h, w), dtype=np.uint16))
    elif mode == "RGB16":  # 16-bit RGB written by hand (Pillow cannot save it)
        raw = b"".join(b"\x00" + rng.integers(0, 256, w * 6, dtype=np.uint8).tobytes()
                       for _ in range(h))
        return _png_chunks(w, h, 16, 2, raw)
    elif mode == "P":
        im = Image.fromarray(rng.integers(0, 256, (h, w, 3), dtype=np.uint8)).convert("P")
    elif mode == "1":
        im = Image.fromarray(rng.integers(0, 2, (h, w), dtype=np.uint8) * 255).convert("1")
    else:
        bands = {"RGB": 3, "RGBA": 4, "L": 1, "LA": 2}[mode]
        arr = rng.integers(0, 256, (h, w, bands), dtype=np.uint8)
        im = Image.fromarray(arr[..., 0] if bands == 1 else arr, mode)
    buf = io.BytesIO()
    im.save(buf, format="PNG")
    return buf.getvalue()


def _png_chunks(w: int, h: int, depth: int, ctype: int, raw: bytes) -> bytes:
    import struct

    def chunk(tag: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + tag + data + \
            struct.pack(">I", zlib.crc32(tag + data))

    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, depth, ctype,
                                                             0, 0, 0))
            + chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b""))


face_damage = st.one_of(
    st.just(("ok",)), st.just(("ok",)), st.just(("ok",)),
    st.just(("missing",)), st.just(("empty",)), st.just(("folder",)),
    st.tuples(st.just("truncate"), st.floats(0, 1)),
    st.tuples(st.just("flip"), st.integers(0, 10_000), st.integers(1, 255)),
    st.tuples(st.just("random"), st.binary(max_size=64)),
    st.tuples(st.just("header"), st.integers(0, 2**32 - 1), st.integers(0, 2**32 - 1)),
)
FACES = ("left", "right", "up", "down", "front", "back")


@fuzz_settings(300)
@given(mode=st.sampled_from(["RGB", "RGBA", "L", "LA", "P", "1", "I;16", "RGB16"]),
       sizes=st.lists(st.tuples(st.integers(1, 5), st.integers(1, 5)), min_size=6, max_size=6),
       # per face: intact or damaged; or all intact; or only the last face damaged
       damage=st.lists(st.one_of(st.just(("ok",)), face_damage), min_size=6, max_size=6).flatmap(
           lambda d: st.sampled_from([d, [("ok",)] * 6, [("ok",)] * 5 + d[:1]])),
       seed=st.integers(0, 99),
       render=st.booleans())
def test_cube_map_faces(mode, sizes, damage, seed, render):
    with tempfile.TemporaryDirectory() as d:
        sky = Path(d) / "sky"
        sky.mkdir()
        for name, size, dmg in zip(FACES, sizes, damage):
            data = png_bytes(mode, size, seed)
            kind = dmg[0]
            if kind == "missing":
                continue
            if kind == "folder":
                (sky / f"{name}.png").mkdir()
                continue
            if kind == "empty":
                data = b""
            elif kind == "truncate":
                data = data[:int(len(data) * dmg[1])]
            elif kind == "flip":
                b = bytearray(data)
                b[dmg[1] % len(b)] ^= dmg[2]
                data = bytes(b)
            elif kind == "random":
                data = dmg[1]
            elif kind == "header":  # IHDR width and height (CRC then fails, or is fixed)
                import struct
                b = bytearray(data)
                b[16:24] = struct.pack(">II", dmg[1], dmg[2])
                b[29:33] = struct.pack(">I", zlib.crc32(bytes(b[12:29])))
                data = bytes(b)
            (sky / f"{name}.png").write_bytes(data)
        scene_path = Path(d) / "s.txt"
        text = ("PerspectiveCamera { center 0 0 0 direction 0 0 -1 up 0 1 0 angle 150 }\n"
                "Background { cubeMap sky }\n")
        scene = parse_checked(text, scene_path, [])
        if scene is None:
            return
        faces = scene.background.cube_map.faces
        for name in FACES:
            f = faces[name]
            assert f.dtype == np.float32 and f.ndim == 3 and f.shape[2] == 3 and f.size > 0
            assert float(f.min()) >= 0.0 and float(f.max()) <= 1.0
        if render:
            img = Renderer(scene, RenderOptions(5, 5, bounces=0)).render().color
            assert img.shape == (5, 5, 3) and np.isfinite(img).all()
            assert float(img.min()) >= 0.0 and float(img.max()) <= 1.0
            event("rendered")


# --- parse and render: hostile numbers end to end --------------------------------------------
RENDER_SCENES = [p for p in SCENE_FILES if p.stem in (
    "spheres_mirror", "axes", "ellipsoid", "triangle", "falloff", "transformed_plane", "rotate",
    "matrix4f", "shadows", "smooth_mesh", "cube_directional", "bounces")]
RENDER_NUMBERS = ["1e39", "-1e39", "3.4028235e38", "1e-50", "1e-45", "0", "-0", "1e20", "1e-20",
                  "1e308", "99999999"]


@fuzz_settings(120)
@given(path=st.sampled_from(RENDER_SCENES), data=st.data(),
       shadows=st.booleans(), bounces=st.integers(0, 2), size=st.integers(1, 4))
def test_hostile_numbers_render_without_crashing(path, data, shadows, bounces, size):
    """Numbers out of float32's range become ±inf (or 0) as C's strtof gives them; such scenes
    render, with whatever NaN/inf the course arithmetic produces, and never crash."""
    parts = re.split(r"(\s+)", CORPUS[path])
    nums = [k for k in range(0, len(parts), 2)
            if re.fullmatch(r"[-+]?[0-9.]+(e[-+]?[0-9]+)?", parts[k])]
    for _ in range(data.draw(st.integers(1, 3))):
        k = data.draw(st.sampled_from(nums))
        parts[k] = data.draw(st.sampled_from(RENDER_NUMBERS))
    text = "".join(parts)
    scene = parse_checked(text, path)
    if scene is None:
        return
    opts = RenderOptions(size, size + 1, bounces=bounces, shadows=shadows,
                         kinds=("color", "normals", "depth"), depth_min=0, depth_max=10)
    # The host-side set-up (camera frame, flattening, BVH) may meet inf/NaN; numpy's warnings
    # about that are silenced by the command line (cli.main), as here.
    with np.errstate(all="ignore"):
        result = Renderer(scene, opts).render()
    event("NaN in the color image" if np.isnan(result.color).any() else "no NaN")
    assert result.color.shape == (size + 1, size, 3)
    assert result.depth.shape == (size + 1, size)


# --- the command line ------------------------------------------------------------------------
GOOD_SCENE = ("PerspectiveCamera { center 0 0 10 direction 0 0 -1 up 0 1 0 angle 30 }\n"
              "Lights { numLights 1 DirectionalLight { direction -1 -1 -1 color 1 1 1 } }\n"
              "Materials { numMaterials 1 Material { diffuseColor 1 0 0 specularColor 1 1 1 } }\n"
              "Group { numObjects 2 MaterialIndex 0 Sphere { center 0 0 0 radius 2 }\n"
              "  Plane { normal 0 1 0 offset -2 } }\n")


@pytest.fixture(scope="module")
def cli_dir(tmp_path_factory) -> Path:
    d = tmp_path_factory.mktemp("cli")
    (d / "good.txt").write_text(GOOD_SCENE)
    (d / "bad.txt").write_text(GOOD_SCENE.replace("radius 2", "radius two"))
    (d / "scene.obj").write_text(GOOD_SCENE)
    (d / "folder.txt").mkdir()
    (d / "out").mkdir()
    (d / "out" / "exists.png").mkdir()  # an output name that is a folder
    return d


size_arg = st.one_of(st.integers(1, 8).map(str), st.integers(1, 8).map(str),
                     st.sampled_from(["0", "-1", "-8", "16385", "100000", "99999999999999999999",
                                      "9" * 5000, "1e3", "2.0", "abc", "", "\u0663", " 4",
                                      "0x8", "+3", "0003"]))
num_arg = st.one_of(st.floats(-20, 20, allow_nan=False).map(lambda x: f"{x:g}"),
                    st.sampled_from(["nan", "inf", "-inf", "1e39", "-1e39", "1e-50", "x", "",
                                     "1.2.3", "9" * 400]))
out_arg = st.sampled_from(["OUT/a.png", "OUT/b.PNG", "OUT/n.png", "OUT/d.png", "OUT/a.jpg",
                           "OUT/a", "OUT/missing/a.png", "OUT/exists.png", "OUT/.png",
                           "OUT/a b.png", "OUT/new\nline.png", "-output"])
in_arg = st.sampled_from(["DIR/good.txt", "DIR/good.txt", "DIR/good.txt", "DIR/bad.txt",
                          "DIR/missing.txt", "DIR/scene.obj", "DIR/folder.txt", "", "-input",
                          "DIR/good.txt\x00"])
flag_item = st.one_of(
    st.tuples(st.just("-input"), in_arg),
    st.tuples(st.just("-output"), out_arg),
    st.tuples(st.just("-normals"), out_arg),
    st.tuples(st.just("-depth"), num_arg, num_arg, out_arg),
    st.tuples(st.just("-size"), size_arg, size_arg),
    st.tuples(st.just("-bounces"), st.one_of(st.integers(0, 3).map(str), st.sampled_from(
        ["-1", "64", "65", "1000", "x", "1.5", "99999999999999999999"]))),
    st.sampled_from([("-shadows",), ("-jitter",), ("-filter",), ("--float",), ("--quiet",)]),
    st.tuples(st.just("--backend"), st.sampled_from(["llvm", "cuda", "opengl", ""])),
    st.tuples(st.just("--precision"), st.sampled_from(["single", "double", "half"])),
    st.tuples(st.just("--seed"), st.sampled_from(["0", "7", "-1", "x", "\u00b2",
                                                   "99999999999999999999", "9" * 5000])),
    st.tuples(st.just("--samples"), st.sampled_from(["1", "2", "0", "4097", "x", "9" * 30])),
    st.sampled_from([("--seed=3",), ("--float=1",), ("--bogus",), ("-antialias",), ("--",),
                     ("-",), ("",), ("\x1b[2J",)]),
)


VALID_BASE = [("-input", "DIR/good.txt"), ("-output", "OUT/a.png")]
command_line = st.one_of(
    st.lists(flag_item, min_size=0, max_size=7),  # anything
    st.tuples(st.lists(flag_item, max_size=4), st.permutations(VALID_BASE)).map(
        lambda t: [*t[1], *t[0]]),  # a valid core with random additions
    st.tuples(st.lists(flag_item, max_size=3), st.permutations(VALID_BASE)).flatmap(
        lambda t: st.permutations([*t[1], *t[0]])),  # the same in random order
)


@fuzz_settings(300)
@given(items=command_line, drop=st.one_of(st.just(-1), st.integers(-1, 30)))
def test_command_line(items, drop, cli_dir, capfd):
    out = cli_dir / "out"
    argv = [a.replace("DIR", str(cli_dir)).replace("OUT", str(out)) for it in items for a in it]
    if 0 <= drop < len(argv):  # a missing argument somewhere
        del argv[drop]
    for p in out.glob("*"):
        if p.is_file():
            p.unlink()
    before = sorted(os.listdir(out))
    capfd.readouterr()
    code = tracer_main(argv)
    captured = capfd.readouterr()
    event(f"exit {code}")
    assert code in (0, 2), (argv, code, captured.err)
    after = sorted(os.listdir(out))
    if code == 2:
        assert captured.err.count("\n") == 1 and captured.err.endswith("\n"), (argv, captured.err)
        assert captured.err.startswith(("python -m raycheck.tracer: error: ", "usage: "))
        assert captured.err[:-1].isprintable(), repr(captured.err)
        assert after == before, (argv, captured.err)  # no output file, no temporary left
    else:
        cmd = parse_course_flags(argv, EXTRA_OPTIONS)
        # nothing with --quiet; else nothing but the progress lines of a render that passes one
        # second (a cold kernel cache, a loaded machine)
        lines = captured.err.splitlines()
        assert not (lines and cmd.extra.get("quiet")), (argv, captured.err)
        assert all(PROGRESS.fullmatch(line) for line in lines), (argv, captured.err)
        assert not [n for n in after if n.endswith(".part")]
        w, h = cmd.request.size
        for p in cmd.outputs.values():
            assert read_png(p).shape == (h, w, 3)
            if "float" in cmd.extra:
                assert np.load(p.with_suffix(".npy")).shape[:2] == (h, w)
