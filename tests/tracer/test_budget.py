"""Memory and work are bounded before any work starts: the estimate of a render's images and
rays, the same for both renderers and every command, refused over the budget with one line
(and an option to raise it); meshes and cube maps refused from their sizes before decoding;
and the estimate is an upper bound of what a render really takes."""
from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest
from PIL import Image

from raycheck.harness.cli import main as raycheck
from raycheck.tracer.scene import SceneError, load_scene
from raycheck.tracer.scene.limits import (
    BYTES_PER_CHANNEL,
    PARSE_BYTES_PER_FACE,
    PARSE_BYTES_PER_VERTEX,
    Budget,
    parse_bytes,
    render_estimate,
)
from raycheck.tracer.scene.request import RenderRequest

REPO = Path(__file__).resolve().parents[2]
ARCH = REPO / "scenes" / "course" / "arch.txt"
FALLOFF = REPO / "scenes" / "features" / "falloff.txt"  # spheres and planes only
SHADOWS = REPO / "scenes" / "features" / "shadows.txt"


def test_the_estimate_counts_pixels_channels_samples_bounces_and_lights():
    r = RenderRequest(10, 20, kinds=("color", "depth"))
    assert render_estimate(r, lights=3) == (200 * 4 * BYTES_PER_CHANNEL, 200)
    r = RenderRequest(10, 20, filter=True, jitter=True, samples=16, bounces=2, shadows=True)
    # 9 sub-pixels each, 16 samples, 1 + 2 levels, each with 1 + 3 shadow rays
    assert render_estimate(r, lights=3) == (1800 * 3 * BYTES_PER_CHANNEL,
                                            1800 * 16 * 3 * 4)


def test_sizes_read_like_a_user_writes_them():
    assert parse_bytes("8G") == 8 << 30 and parse_bytes("512M") == 512 << 20
    assert parse_bytes("1.5GiB") == 3 << 29 and parse_bytes("100") == 100
    for bad in ("0", "x", "-1G", "1e3"):
        with pytest.raises(ValueError):
            parse_bytes(bad)


@pytest.mark.parametrize("command", ["render", "reference", "compare"])
def test_a_render_over_the_memory_budget_is_refused_with_the_option_to_raise_it(
        command, tmp_path, capsys):
    argv = [command, "-input", str(FALLOFF), "-size", "100", "100", "-output",
            str(tmp_path / "a.png"), "--max-memory", "100K"]
    if command == "compare":
        argv += ["--out", str(tmp_path / "c")]
    assert raycheck(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--max-memory raises it" in err
    # 100x100 color: 10000 * 3 * 20 bytes = 585.9 KiB
    assert "about 0.6 MiB" in err and "limit of 0.1 MiB" in err
    assert list(tmp_path.iterdir()) == []


def test_a_render_over_the_ray_budget_is_refused(tmp_path, capsys):
    assert raycheck(["render", "-input", str(FALLOFF), "-size", "100", "100", "-jitter",
                     "-bounces", "3", "-output", str(tmp_path / "a.png"),
                     "--max-rays", "100000"]) == 2
    err = capsys.readouterr().err
    # 10^4 pixels x 16 samples x 4 levels = 640,000 rays
    assert "casts up to 6.4e+05 rays, over the limit of 1e+05" in err and not list(
        tmp_path.iterdir())


def test_check_refuses_a_case_over_the_budget_before_running_any(tmp_path, capsys):
    code = raycheck(["check", "--renderer", "tracer", str(SHADOWS), "--size", "64", "64",
                     "--max-memory", "500K", "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1 and "shadows.txt: plain:" in err
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("over", ["sweep", "case"])
def test_report_refuses_a_sweep_or_case_over_the_budget_before_any_work(over, tmp_path, capsys,
                                                                        monkeypatch):
    """Before the stress and bench pages and the cases (the sweep's limit was found only after
    every case had run): one line, exit 2, no output folder. The sweep's first render over
    2e5 rays is its 1024-sample reference at 64x64 (the estimate: 6.29e7 rays); the 4x4 cases
    stay under it, and a limit of 1000 stops the first case that is over it."""
    from raycheck.harness.commands import report

    monkeypatch.setattr(report, "run_matrix", lambda *a, **k: pytest.fail("cases ran"))
    scene = REPO / "scenes" / "course" / "spheres_mirror.txt"
    argv = ["report", str(scene), "--out", str(tmp_path / "out"), "--size", "4", "--quiet",
            "--no-bench", "--max-rays", "200000" if over == "sweep" else "1000"]
    assert raycheck(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--max-rays raises it" in err
    if over == "sweep":
        assert ("error-against-time sweep of spheres_mirror, 64x64 at 1024 samples: the render "
                "casts up to 6.29e+07 rays") in err and "--no-sweeps" in err
    else:
        # 4x4 x 3x3 sub-pixels x 16 samples = 2304 rays, the first case over 1000
        assert "spheres_mirror.txt: jitter+filter: the render casts up to 2.3e+03 rays" in err
    assert not (tmp_path / "out").exists()


def _mesh_scene(tmp_path: Path, faces: int) -> Path:
    rows = ["v 0 0 0", "v 1 0 0", "v 0 1 0"] + ["f 1 2 3"] * faces
    (tmp_path / "m.obj").write_text("\n".join(rows) + "\n")
    text = SHADOWS.read_text().replace("../assets/cube_flat.obj", "m.obj")
    scene = tmp_path / "s.txt"
    scene.write_text(text.replace("../assets", str(REPO / "scenes" / "assets")))
    return scene


def test_a_mesh_over_the_budget_is_refused_from_its_face_count(tmp_path):
    scene = _mesh_scene(tmp_path, 1000)
    assert "TriangleMesh" in scene.read_text() and "m.obj" in scene.read_text()
    need = 1000 * PARSE_BYTES_PER_FACE + 3 * PARSE_BYTES_PER_VERTEX
    with pytest.raises(SceneError, match=r"m.obj \(1000 faces\) needs about 0\.7 MiB"):
        load_scene(scene, Budget(memory_bytes=need - 1))
    load_scene(scene, Budget(memory_bytes=need))  # exactly the estimate: read


def test_a_cube_map_over_the_budget_is_refused_from_its_headers(tmp_path, monkeypatch):
    sky = tmp_path / "sky"
    sky.mkdir()
    for name in ("left", "right", "up", "down", "front", "back"):
        Image.new("RGB", (64, 32)).save(sky / f"{name}.png")
    scene = tmp_path / "s.txt"
    scene.write_text((REPO / "scenes" / "features" / "cubemap.txt").read_text()
                     .replace("../assets/sky", str(sky))
                     .replace("../assets", str(REPO / "scenes" / "assets")))
    decoded = []
    import raycheck.tracer.scene.cubemap as cubemap

    real = cubemap.load_face
    monkeypatch.setattr(cubemap, "load_face", lambda *a: decoded.append(a) or real(*a))
    # 12288 texels x 39 bytes (limits.BYTES_PER_TEXEL) = 0.46 MiB
    with pytest.raises(SceneError, match=r"\(12288 texels\) needs about 0\.5 MiB"):
        load_scene(scene, Budget(memory_bytes=100_000))
    assert decoded == []  # no face was decoded
    load_scene(scene)
    assert len(decoded) == 6


def _peak_rss(argv: list[str]) -> int:
    """Peak resident memory in bytes of `python -m raycheck.tracer argv` in a child: its VmHWM,
    not ru_maxrss, which Linux carries over exec from the forked parent (pytest, ~200 MB
    after collecting the whole suite) and so hides a smaller render."""
    # main() rather than the module: `python -m raycheck.tracer` ends its process at once
    code = ("import re, sys; from raycheck.tracer.cli import main\n"
            "assert main(sys.argv[1:]) == 0\n"
            "print(re.search(r'VmHWM:\\s*(\\d+)', open('/proc/self/status').read())[1])")
    out = subprocess.run([sys.executable, "-c", code, *argv], capture_output=True, text=True,
                         check=True)
    return int(out.stdout.split()[-1]) * 1024


def test_a_renders_memory_stays_under_its_estimate(tmp_path):
    """What a render adds to a process (peak RSS of a 1024x1024 render of every kind minus
    that of a 4x4 one, the same kernel, compiled by the first and cached for the second) is
    at most the estimate the budget is checked against."""
    base = ["-input", str(ARCH), "-output", str(tmp_path / "a.png"), "-normals",
            str(tmp_path / "n.png"), "-depth", "6", "16", str(tmp_path / "d.png"), "--quiet"]
    small = _peak_rss(["-size", "4", "4", *base])
    big = _peak_rss(["-size", "1024", "1024", *base])
    estimate, _ = render_estimate(RenderRequest(1024, 1024, kinds=("color", "normals",
                                                                    "depth")), lights=2)
    assert 0 < big - small <= estimate, (big - small, estimate)
