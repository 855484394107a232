"""The course command line (spec §10) through `python -m raycheck.tracer` / `raycheck render`."""
from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import red_sphere

from raycheck.harness.cli import main as raycheck_main
from raycheck.tracer.cli import main as tracer_main
from raycheck.tracer.image import read_png


@pytest.fixture()
def scene(tmp_path: Path) -> Path:
    return red_sphere.write(tmp_path)


def run(argv: list[str], capsys) -> tuple[int, str]:
    code = tracer_main([str(a) for a in argv])
    return code, capsys.readouterr().err


def test_course_command_line_writes_three_images(scene: Path, tmp_path: Path, capsys):
    out, nrm, dep = tmp_path / "a.png", tmp_path / "n.png", tmp_path / "d.png"
    code, err = run(["-size", 9, 7, "-input", scene, "-bounces", 2, "-shadows", "-output", out,
                     "-normals", nrm, "-depth", 8, 10, dep], capsys)
    # stderr may hold the progress line (a loaded machine passes its one second), nothing else
    assert code == 0 and all(line.startswith("rendering:") for line in err.splitlines()), err
    for p in (out, nrm, dep):
        assert read_png(p).shape == (7, 9, 3)
    # the center pixel hits the sphere head-on: t = 8, normal (0,0,1), depth (8-8)/2 = 0
    assert read_png(dep)[3, 4].tolist() == [0, 0, 0]
    assert read_png(nrm)[3, 4].tolist() == [127, 127, 255]
    # corners miss: background blue, normals 127, depth black (FLT_MAX)
    assert read_png(out)[0, 0].tolist() == [0, 0, 255]
    assert read_png(nrm)[0, 0].tolist() == [127, 127, 127]
    assert read_png(dep)[0, 0].tolist() == [0, 0, 0]


def test_flags_in_any_order_later_repeat_wins(scene: Path, tmp_path: Path, capsys):
    out = tmp_path / "a.png"
    code, _ = run(["-output", tmp_path / "first.png", "-size", 3, 3, "-input", scene,
                   "-size", 5, 4, "-output", out], capsys)
    assert code == 0
    assert read_png(out).shape == (4, 5, 3)
    assert not (tmp_path / "first.png").exists()


def test_only_named_images_are_written(scene: Path, tmp_path: Path, capsys):
    code, _ = run(["-input", scene, "-size", 4, 4, "-normals", tmp_path / "n.png"], capsys)
    assert code == 0
    assert sorted(p.name for p in tmp_path.iterdir()) == ["n.png", "scene.txt"]


@pytest.mark.parametrize("argv, message", [
    (["-input", "{scene}", "-output", "{out}", "-size", "4"], "-size needs 2 arguments"),
    (["-input", "{scene}", "-output", "{out}", "-size", "0", "4"],
     "-size: expected an integer >= 1, found '0'"),
    (["-input", "{scene}", "-output", "{out}", "-bounces", "-1"],
     "-bounces: expected an integer >= 0, found '-1'"),
    (["-input", "{scene}", "-output", "{out}", "-depth", "a", "1", "{out}"],
     "-depth: expected a number, found 'a'"),
    (["-input", "{scene}", "-output", "{out}", "-antialias"], "unknown flag '-antialias'"),
    (["-output", "{out}"], "-input scene.txt is required"),
    (["-input", "{scene}"], "nothing to write: give -output, -normals or -depth"),
    (["-input", "{scene}", "-output", "{tmp}/missing/a.png"], "folder of output file"),
    (["-input", "{scene}", "-output", "{tmp}/a.jpg"], "output file names must end in .png"),
    (["-input", "{scene}", "-output", "{out}", "-size", "20000", "20"],
     "image size 20000x20 is outside 1..16384 per side"),
    (["-input", "{scene}", "-output", "{out}", "-bounces", "1000"],
     "bounces 1000 is outside 0..64"),
    (["-input", "{scene}", "-output", "{out}", "--backend", "opengl"], "unknown backend 'opengl'"),
    (["-input", "{scene}", "-output", "{out}", "--seed", "x"], "--seed: expected a non-negative"),
    (["-input", "{scene}", "-output", "{out}", "--fast"], "unknown option '--fast'"),
])
def test_bad_flags_one_line_exit_2_no_output(argv, message, scene: Path, tmp_path: Path, capsys):
    out = tmp_path / "a.png"
    args = [a.format(scene=scene, out=out, tmp=tmp_path) for a in argv]
    code, err = run(args, capsys)
    assert code == 2
    assert err.count("\n") == 1 and err.startswith("python -m raycheck.tracer: error: ")
    assert message in err
    assert not out.exists()


def test_bad_scene_names_file_and_line_and_keeps_old_output(tmp_path: Path, capsys):
    bad = tmp_path / "bad.txt"
    bad.write_text(red_sphere.TEXT.replace("radius 2", "radius two"))
    out = tmp_path / "a.png"
    out.write_bytes(b"previous")
    code, err = run(["-input", bad, "-output", out], capsys)
    assert code == 2
    assert err == (f"python -m raycheck.tracer: error: {bad}:5: "
                   "expected a number for radius, found 'two'\n")
    assert out.read_bytes() == b"previous"


def test_float_output_matches_png(scene: Path, tmp_path: Path, capsys):
    out = tmp_path / "a.png"
    code, _ = run(["-input", scene, "-size", 6, 5, "-output", out, "--float"], capsys)
    assert code == 0
    floats = np.load(tmp_path / "a.npy")
    assert floats.shape == (5, 6, 3) and floats.dtype == np.float32
    from raycheck.tracer.image import to_rgb8
    assert np.array_equal(to_rgb8(floats), read_png(out))


def test_float_files_that_cannot_be_written_apart_are_refused_before_rendering(
        scene: Path, tmp_path: Path, capsys):
    """A folder where a.npy goes, and two images whose values would share one .npy: exit 2,
    one line, and no file written (the PNG was written before the .npy failed, once)."""
    (tmp_path / "g.npy").mkdir()
    code, err = run(["-input", scene, "-size", 4, 4, "-output", tmp_path / "g.png", "--float"],
                    capsys)
    assert (code, err) == (2, f"python -m raycheck.tracer: error: output file "
                              f"'{tmp_path / 'g.npy'}' is a folder\n")
    code, err = run(["-input", scene, "-size", 4, 4, "-output", tmp_path / "a.png",
                     "-normals", tmp_path / "a.exr", "--float"], capsys)
    assert (code, err) == (2, "python -m raycheck.tracer: error: --float: the color and "
                              f"normals images' values would both be written to "
                              f"'{tmp_path / 'a.npy'}'\n")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["g.npy", "scene.txt"]


def test_jitter_is_reproducible_and_seedable(scene: Path, tmp_path: Path, capsys):
    def jitter(name: str, *extra: str) -> np.ndarray:
        path = tmp_path / f"{name}.png"
        assert run(["-input", scene, "-size", 8, 8, "-jitter", "-output", path, "--float",
                    *extra], capsys)[0] == 0
        return np.load(tmp_path / f"{name}.npy")

    a, b = jitter("a"), jitter("b")
    c = jitter("c", "--seed", "7")
    assert np.array_equal(a, b)
    assert not np.array_equal(a, c)


def test_python_m_tracer_and_raycheck_info(scene: Path, tmp_path: Path):
    out = tmp_path / "a.png"
    proc = subprocess.run([sys.executable, "-m", "raycheck.tracer", "-input", str(scene),
                           "-size", "4",
                           "4", "-output", str(out)], capture_output=True, text=True)
    assert proc.returncode == 0 and out.exists(), proc.stderr
    proc = subprocess.run([sys.executable, "-m", "raycheck.tracer",
                           "-input", str(tmp_path / "x.txt"),
                           "-output", str(out)], capture_output=True, text=True)
    assert proc.returncode == 2
    assert proc.stderr == (f"python -m raycheck.tracer: error: {tmp_path / 'x.txt'}: "
                           "scene file not found\n")


def test_raycheck_info(scene: Path, capsys):
    assert raycheck_main(["info", str(scene)]) == 0
    text = capsys.readouterr().out
    assert "1 spheres, 0 planes, 0 triangles, 0 meshes" in text
    assert "-bounces  mirror recursion on materials 0" in text
    assert "-shadows  shadow rays from every lit point" in text


def test_raycheck_render_and_bad_command(scene: Path, tmp_path: Path, capsys):
    out = tmp_path / "a.png"
    assert raycheck_main(["render", "-input", str(scene), "-size", "3", "3",
                          "-output", str(out)]) == 0
    assert read_png(out).shape == (3, 3, 3)
    assert raycheck_main(["frobnicate"]) == 2
    assert "unknown command 'frobnicate'" in capsys.readouterr().err


def test_outputs_get_the_mode_open_would_give(scene: Path, tmp_path: Path, capsys):
    import os

    out = tmp_path / "a.png"
    umask = os.umask(0o022)
    try:
        assert run(["-input", scene, "-size", 3, 3, "-output", out], capsys)[0] == 0
    finally:
        os.umask(umask)
    assert out.stat().st_mode & 0o777 == 0o644  # not the temporary file's private 0600


# What a render never needs: the reference renderer, image metrics, the harness's own packages
# and importlib.metadata (start-up time: docs/performance.md).
NOT_FOR_RENDER = ("mitsuba", "skimage", "flip_evaluator", "OpenEXR", "scipy",
                  "raycheck.harness.renderers", "raycheck.harness.pipeline",
                  "raycheck.harness.judge", "importlib.metadata")


@pytest.mark.parametrize("entry", [["-m", "raycheck.tracer"],
                                   ["-c", "import sys; from raycheck.harness.cli import main; "
                                          "sys.exit(main(['render', *sys.argv[1:]]))"]],
                         ids=["python-m-tracer", "raycheck-render"])
def test_a_render_imports_nothing_it_does_not_need(entry, scene: Path, tmp_path: Path):
    out = tmp_path / "a.png"
    proc = subprocess.run([sys.executable, "-X", "importtime", *entry, "-input", str(scene),
                           "-size", "4", "4", "-output", str(out), "--quiet"],
                          capture_output=True, text=True)
    assert proc.returncode == 0 and out.is_file(), proc.stderr[-2000:]
    imported = {line.rsplit("|", 1)[-1].strip() for line in proc.stderr.splitlines()
                if line.startswith("import time:")}
    assert "drjit" in imported  # the probe sees the imports
    assert not {m for m in imported for bad in NOT_FOR_RENDER
                if m == bad or m.startswith(bad + ".")}
    assert "PIL" not in imported  # PNGs are written by scene.outputs; Pillow reads cube maps


def test_a_deterministic_check_against_the_tracer_loads_neither_mitsuba_nor_scipy_stats(
        scene: Path, tmp_path: Path):
    """scipy.stats (~0.9 s to import) judges jittered images only, and the engines' source
    digest finds mitsuba_ref without importing it (which loads Mitsuba)."""
    proc = subprocess.run([sys.executable, "-X", "importtime", "-m", "raycheck.harness", "check",
                           "--renderer", "tracer", str(scene), "--features", "plain",
                           "--size", "8", "8", "--out", str(tmp_path / "out"), "--quiet"],
                          capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr[-2000:]
    imported = {line.rsplit("|", 1)[-1].strip() for line in proc.stderr.splitlines()
                if line.startswith("import time:")}
    assert "raycheck.harness.judge.statistics" in imported  # the probe sees the imports
    assert not {m for m in imported for bad in ("mitsuba", "raycheck.mitsuba_ref", "scipy.stats")
                if m == bad or m.startswith(bad + ".")}


@pytest.mark.parametrize("shape", [(1, 1), (1, 7), (5, 1), (33, 47)])
def test_written_png_holds_the_exact_pixels(shape, tmp_path: Path):
    from PIL import Image

    from raycheck.tracer.scene.outputs import write_png_rgb8

    rgb = np.random.default_rng(sum(shape)).integers(0, 256, shape + (3,), dtype=np.uint8)
    rgb[0, 0] = [255, 0, 1]  # Sub-filter differences that wrap around 256 both ways
    if shape[1] > 1:
        rgb[0, 1] = [0, 255, 0]
    path = tmp_path / "x.png"
    write_png_rgb8(str(path), rgb)
    with Image.open(path) as im:
        assert (im.format, im.mode, im.size) == ("PNG", "RGB", (shape[1], shape[0]))
        assert np.array_equal(np.asarray(im), rgb)
