"""`python -m raycheck.mitsuba_ref` / `raycheck reference` and `raycheck export`
(mitsuba_ref.cli, .export).

Same contract as the tracer's command line: the course's flags, three images (plus .npy floats
with --float), bad input -> one line on stderr, exit status 2, no output file touched. Exported
XML files load with mi.load_file once mitsuba_ref is imported and render the same image.
"""
from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

import mitsuba as mi
import numpy as np
import pytest
import red_sphere
from PIL import Image

import raycheck.mitsuba_ref  # noqa: F401  (registers the plugins)
from raycheck.harness.catalog import bundled
from raycheck.mitsuba_ref.cli import main
from raycheck.mitsuba_ref.export import main_export, write_xml
from raycheck.mitsuba_ref.image import rgb_bytes
from raycheck.mitsuba_ref.render import ReferenceOptions, ReferenceRenderer
from raycheck.mitsuba_ref.translate import Settings
from raycheck.tracer.scene import load_scene

REPO = Path(__file__).resolve().parents[2]


@pytest.fixture()
def scene(tmp_path: Path) -> Path:
    return red_sphere.write(tmp_path)


def run(argv, capsys, prog="raycheck reference") -> tuple[int, str]:
    code = main([str(a) for a in argv], prog=prog)
    return code, capsys.readouterr().err


def test_course_command_line_writes_three_images_and_floats(scene: Path, tmp_path: Path, capsys):
    out, nrm, dep = tmp_path / "a.png", tmp_path / "n.png", tmp_path / "d.png"
    code, err = run(["-size", 9, 7, "-input", scene, "-bounces", 2, "-shadows", "-output", out,
                     "-normals", nrm, "-depth", 8, 10, dep, "--float", "--quiet"], capsys)
    assert (code, err) == (0, "")
    for png in (out, nrm, dep):
        pixels = np.asarray(Image.open(png).convert("RGB"))
        assert pixels.shape == (7, 9, 3)
        floats = np.load(png.with_suffix(".npy"))
        np.testing.assert_array_equal(pixels, rgb_bytes(floats))
    color = np.load(out.with_suffix(".npy"))
    # row 0 = top; the sphere fills the middle, the background (blue) the corners
    assert color[0, 0].tolist() == [0, 0, 1] and color[3, 4, 0] > 0.9
    assert np.asarray(Image.open(nrm))[3, 4].tolist() == [127, 127, 255]
    assert np.load(dep.with_suffix(".npy"))[3, 4] == pytest.approx(0.0, abs=1e-5)  # t = 8 = min


def test_only_named_images_are_written(scene: Path, tmp_path: Path, capsys):
    code, _ = run(["-input", scene, "-size", 4, 4, "-depth", 8, 10, tmp_path / "d.png"], capsys)
    assert code == 0
    assert sorted(p.name for p in tmp_path.iterdir()) == ["d.png", "scene.txt"]


@pytest.mark.parametrize("argv, message", [
    (["-size", 4, 4], "-input scene.txt is required"),
    (["-input", "SCENE", "-size", 0, 4, "-output", "OUT/a.png"], "-size"),
    (["-input", "SCENE", "-output", "OUT/a.jpg"], "must end in .png"),
    (["-input", "SCENE"], "nothing to write"),
    (["-input", "SCENE", "-output", "OUT/no/a.png"], "does not exist"),
    (["-input", "SCENE", "-output", "OUT/a.png", "--variant", "scalar_rgb"], "--variant"),
    (["-input", "SCENE", "-output", "OUT/a.png", "--offsets", "none"], "--offsets"),
    (["-input", "SCENE", "-output", "OUT/a.png", "--seed", "-1"], "--seed"),
    (["-input", "SCENE", "-output", "OUT/a.png", "-bounces", 65], "bounces"),
    (["-input", "SCENE", "-output", "OUT/a.png", "--bogus"], "unknown option"),
    (["-input", "OUT/missing.txt", "-output", "OUT/a.png"], "missing.txt"),
    (["-input", "BROKEN", "-output", "OUT/a.png"], "broken.txt:1"),
    (["-input", "SCENE", "-output", "OUT/dir.png"], "is a folder"),
    (["-input", "SCENE", "-output", "OUT/a.png", "--samples", "٣"], "--samples"),
    (["-input", "SCENE", "-output", "OUT/a.png", "-filter", "-size", 16384, 16384],
     "over the limit"),
])
def test_bad_input_is_one_line_exit_2_and_no_file(argv, message, scene: Path, tmp_path: Path,
                                                  capsys):
    broken = tmp_path / "broken.txt"
    broken.write_text("PerspectiveCamera { center 0 0 oops }\n")
    (tmp_path / "dir.png").mkdir()
    argv = [str(a).replace("SCENE", str(scene)).replace("BROKEN", str(broken))
            .replace("OUT", str(tmp_path)) for a in argv]
    code, err = run(argv, capsys)
    assert code == 2
    assert err.count("\n") == 1 and err.startswith("raycheck reference: error:")
    assert message in err
    assert "Traceback" not in err
    assert not [p for p in tmp_path.glob("*.png") if p.is_file()]


def test_help_goes_to_stdout_and_no_arguments_is_a_usage_error(capsys):
    assert main(["--help"], prog="raycheck reference") == 0
    out, err = capsys.readouterr()
    assert out.startswith("usage: raycheck reference -input") and err == ""
    assert main([], prog="raycheck reference") == 2
    out, err = capsys.readouterr()
    assert out == "" and err.startswith("usage:")


def test_cuda_variant_without_a_gpu_is_a_clear_error(scene: Path, tmp_path: Path, capsys):
    import drjit as dr

    if dr.has_backend(dr.JitBackend.CUDA):
        pytest.skip("this machine has a GPU")
    code, err = run(["-input", scene, "-output", tmp_path / "a.png", "--variant",
                     "cuda_ad_rgb"], capsys)
    assert code == 2 and "needs a CUDA GPU" in err and err.count("\n") == 1


def test_python_dash_m_runs_the_same_command(scene: Path, tmp_path: Path):
    out = tmp_path / "a.png"
    proc = subprocess.run([sys.executable, "-m", "raycheck.mitsuba_ref", "-input", str(scene),
                           "-size", "5", "5", "-output", str(out)],
                          capture_output=True, text=True, cwd=REPO, timeout=120)
    assert proc.returncode == 0, proc.stderr
    assert np.asarray(Image.open(out)).shape == (5, 5, 3)
    bad = subprocess.run([sys.executable, "-m", "raycheck.mitsuba_ref", "-input", str(scene)],
                         capture_output=True, text=True, cwd=REPO, timeout=120)
    assert bad.returncode == 2 and bad.stderr.count("\n") == 1


# ----------------------------------------------------------------------------- export
def render_xml(path: Path) -> np.ndarray:
    scene = mi.load_file(str(path))
    try:
        return np.array(mi.render(scene), dtype=np.float32)
    finally:
        del scene


def render_dict(scene, **opts) -> np.ndarray:
    r = ReferenceRenderer(scene, ReferenceOptions(kinds=("color", "normals", "depth"), **opts))
    try:
        res = r.render()
    finally:
        r.close()
    return np.concatenate([res.color, res.normals, res.depth[..., None]], axis=-1)


def assert_same_image(a: np.ndarray, b: np.ndarray) -> None:
    # the XML path moves meshes to world space in Mitsuba (float32) instead of on the host
    # (float64): equal up to float32 rounding
    with np.errstate(invalid="ignore", over="ignore"):
        same = (a == b) | (np.isnan(a) & np.isnan(b)) | \
            (np.abs(a - b) <= 1e-4 * np.maximum(1.0, np.abs(b)))
    assert same.mean() >= 0.999 and np.mean(rgb_bytes(a[..., :3]) == rgb_bytes(b[..., :3])) > 0.99


@pytest.mark.parametrize("bs", [b for g in ("course", "features") for b in bundled(g)],
                         ids=lambda b: b.name)
def test_exported_xml_renders_the_same_image_after_moving_the_folder(bs, tmp_path: Path):
    f = bs.flags
    w, h = bs.size or (24, 24)
    bounces = int(f[f.index("-bounces") + 1]) if "-bounces" in f else 0
    lo, hi = bs.depth_range
    shutil.copytree(REPO / "scenes", tmp_path / "a")
    scene = load_scene(tmp_path / "a" / bs.path.parent.name / bs.path.name)
    xml = tmp_path / "a" / "xml" / f"{bs.name}.xml"
    xml.parent.mkdir()
    write_xml(scene, xml, Settings(width=w, height=h, bounces=bounces, shadows="-shadows" in f,
                                   kinds=("color", "normals", "depth"), depth_min=lo,
                                   depth_max=hi))
    want = render_dict(scene, width=w, height=h, bounces=bounces, shadows="-shadows" in f,
                       depth_min=lo, depth_max=hi)
    (tmp_path / "a").rename(tmp_path / "b")  # no absolute path may point back
    got = render_xml(tmp_path / "b" / "xml" / xml.name)
    assert_same_image(got, want)
    assert np.array_equal(rgb_bytes(got[..., :3]), rgb_bytes(want[..., :3]))


def test_export_of_a_smooth_mesh_under_non_uniform_scale_uses_an_instance(tmp_path: Path):
    (tmp_path / "octa.obj").write_text(
        "v 0 1.3 0\nv 1 0 0\nv 0 0 1\nv -1 0 0\nv 0 0 -1\nv 0 -1 0\n"
        "f 1 3 2\nf 1 2 5\nf 1 5 4\nf 1 4 3\nf 6 2 3\nf 6 5 2\nf 6 4 5\nf 6 3 4\n")
    text = red_sphere.TEXT.replace("Sphere { center 0 0 0 radius 2 }",
                         "Transform { ZRotate 20 Scale 2 0.7 1 "
                         "TriangleMesh { obj_file octa.obj } }")
    (tmp_path / "s.txt").write_text(text)
    scene = load_scene(tmp_path / "s.txt")
    xml = tmp_path / "out" / "s.xml"
    xml.parent.mkdir()
    written = write_xml(scene, xml, Settings(width=16, height=16,
                                             kinds=("color", "normals", "depth"),
                                             depth_min=8, depth_max=10))
    assert written[-1] == xml and written[0].suffix == ".ply"
    text = xml.read_text()
    assert 'type="instance"' in text and 'type="shapegroup"' in text
    assert_same_image(render_xml(xml), render_dict(scene, width=16, height=16, depth_min=8,
                                                   depth_max=10))


def test_export_with_jitter_and_filter_renders_the_sub_pixel_film(tmp_path: Path, scene: Path):
    s = load_scene(scene)
    xml = tmp_path / "j.xml"
    write_xml(s, xml, Settings(width=5, height=4, jitter=True, filter=True))
    image = render_xml(xml)
    assert image.shape == (12, 15, 3)  # 3w x 3h; the 1-2-1 kernel is applied by render.py
    r = ReferenceRenderer(s, ReferenceOptions(width=5, height=4, jitter=True, filter=True))
    from raycheck.mitsuba_ref.render import filter_121
    try:
        np.testing.assert_allclose(filter_121(image), r.render().color, rtol=1e-5, atol=1e-6)
    finally:
        r.close()


def test_export_command_line(scene: Path, tmp_path: Path, capsys):
    xml = tmp_path / "scene.xml"
    code = main_export(["-size", "8", "6", str(scene), "-o", str(xml), "-bounces", "2",
                        "-normals", "n.png"])
    assert code == 0 and xml.is_file()
    assert str(xml) in capsys.readouterr().out
    text = xml.read_text()
    assert '<integer name="width" value="8"/>' in text and 'name="normals"' in text
    assert render_xml(xml).shape == (6, 8, 6)
    for argv, message in (([str(scene)], "-o scene.xml is required"),
                          ([str(scene), "-o", str(tmp_path / "x.txt")], "must end in .xml"),
                          ([str(tmp_path / "nope.txt"), "-o", str(xml)], "nope.txt"),
                          ([str(scene), "-o", str(tmp_path / "no" / "x.xml")], "does not exist"),
                          ([str(scene), "-o", str(xml), "-size", "0", "1"], "-size"),
                          ([str(scene), "-o", str(xml), "-bounces", "99"], "bounces 99")):
        code = main_export(argv)
        err = capsys.readouterr().err
        assert code == 2 and message in err and err.count("\n") == 1, err


def test_export_that_fails_midway_leaves_no_mesh_and_no_xml(tmp_path: Path, monkeypatch):
    """The PLYs and the XML are written all or nothing: a full disk while writing the XML
    (the last file) leaves neither the meshes nor their folder behind."""
    import raycheck.mitsuba_ref.export as export

    def full_disk(self, *args, **kwargs):
        raise OSError(28, "No space left on device", str(self))

    monkeypatch.setattr(Path, "write_text", full_disk)
    scene = load_scene(REPO / "scenes" / "course" / "smooth_mesh.txt")
    with pytest.raises(OSError):
        export.write_xml(scene, tmp_path / "s.xml", Settings(width=8, height=8))
    assert list(tmp_path.iterdir()) == []


def test_a_film_rendered_in_bands_is_the_film_rendered_whole(monkeypatch):
    """Above MAX_LAUNCH_LANES samples a film is rendered in bands of rows: the images are
    those of the whole film, bit for bit (deterministic), every kind, with -filter (bands of
    sub-pixel rows)."""
    import raycheck.mitsuba_ref.render as render

    scene = load_scene(REPO / "scenes" / "course" / "spheres_mirror.txt")
    opts = ReferenceOptions(12, 10, bounces=2, shadows=True, filter=True,
                            kinds=("color", "normals", "depth"), depth_min=5, depth_max=15)
    whole = render.render(scene, opts)
    monkeypatch.setattr(render, "MAX_LAUNCH_LANES", 36 * 7)  # 36-wide sub-pixel rows, 7 a band
    r = render.ReferenceRenderer(scene, opts)
    assert r.bands == [(0, 7), (7, 14), (14, 21), (21, 28), (28, 30)]
    banded = r.render()
    r.close()
    for kind in ("color", "normals", "depth"):
        np.testing.assert_array_equal(getattr(banded, kind), getattr(whole, kind))


def test_launches_hold_at_most_max_launch_lanes_samples():
    from raycheck.mitsuba_ref.render import MAX_LAUNCH_LANES, launch_plan

    assert MAX_LAUNCH_LANES == 4_194_304
    # the report's -jitter -filter film: 384 x 384 x 16 = 2,359,296 samples, one launch
    assert launch_plan(384, 384, 16) == ([(0, 384)], [16])
    # 800 x 800 = 640,000 pixels: 6 samples a pass (3,840,000), 6 + 6 + 4
    assert launch_plan(800, 800, 16) == ([(0, 800)], [6, 6, 4])
    # 4096 x 4096 at one sample: bands of 4,194,304 / 4096 = 1024 rows
    assert launch_plan(4096, 4096, 1) == ([(0, 1024), (1024, 2048), (2048, 3072),
                                           (3072, 4096)], [1])
    # wider than a launch: one row a band
    assert launch_plan(5_000_000, 2, 1) == ([(0, 1), (1, 2)], [1])


def test_jittered_samples_are_mitsubas_and_a_nan_sample_keeps_its_pixel_nan():
    """A jittered render takes mi.render's samples (its sampler and seed, our plugins) and
    adds each pixel's in sample order itself: the bits of Mitsuba's film without the local
    pre-reduction of its scatter-adds (one atomic add per sample, in lane order), NaN where
    any of a pixel's samples is NaN (falloff 0), the same every time."""
    import drjit as dr

    from raycheck.mitsuba_ref.render import filter_121
    from raycheck.mitsuba_ref.translate import sampler_seed

    s = load_scene(REPO / "scenes" / "features" / "falloff_zero.txt")
    opts = ReferenceOptions(10, 8, jitter=True, filter=True, seed=7,
                            kinds=("color", "normals", "depth"), depth_min=5.5, depth_max=14)
    r = ReferenceRenderer(s, opts)
    try:
        first, second = r.render(), r.render()
        with dr.scoped_set_flag(dr.JitFlag.ScatterReduceLocal, False):
            film = np.array(mi.render(r.scene, spp=16, seed=sampler_seed(7, 0)))
    finally:
        r.close()
    ours = np.concatenate([first.color, first.normals, first.depth[..., None]], axis=-1)
    theirs = filter_121(film)
    assert np.isnan(ours).any() and not np.isnan(ours).all()
    np.testing.assert_array_equal(ours, theirs)  # NaN where NaN
    for kind in ("color", "normals", "depth"):
        np.testing.assert_array_equal(getattr(first, kind), getattr(second, kind))
