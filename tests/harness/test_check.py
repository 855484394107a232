"""`raycheck check` against real subprocess renderers:
`python -m raycheck.tracer` itself passes every
case, and wrappers around it with one known defect each (tests/wrappers/corrupt.py) fail or err
exactly the cases and image kinds that defect touches, with the exact finding code; a renderer
that times out leaves no process behind; the --renderer string is split like a shell would.

Tiny images (12x12) and few cases: each case starts the candidate as a new process."""
from __future__ import annotations

import hashlib
import io
import json
import os
import shlex
import shutil
import sys
import time
from contextlib import redirect_stderr, redirect_stdout
from dataclasses import dataclass
from html import escape
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from raycheck.harness.cli.check import main as check_main
from raycheck.tracer import cli as tracer_cli

REPO = Path(__file__).resolve().parents[2]
WRAPPERS = REPO / "tests" / "wrappers"
CORRUPT = WRAPPERS / "corrupt.py"
ORPHAN = WRAPPERS / "orphan.py"
SHADOWS = REPO / "scenes" / "features" / "shadows.txt"  # lights, shadows, no mirrors
JITTER_FILTER = REPO / "scenes" / "features" / "jitter_filter.txt"  # bright background
MIRROR = REPO / "scenes" / "course" / "spheres_mirror.txt"  # mirrors: bounces4 cases
MESH = REPO / "scenes" / "course" / "cubemap_mesh.txt"  # a mesh, not transformed
SIZE = ("12", "12")
ALL_KINDS = ("color", "normals", "depth")
# the kinds a feature's case compares (shadows and mirrors change only the color image)
KINDS = {"plain": ALL_KINDS, "shadows": ("color",), "bounces4": ("color",),
         "shadows+bounces4": ("color",), "jitter": ALL_KINDS, "filter": ALL_KINDS,
         "jitter+filter": ALL_KINDS}


@dataclass
class Checked:
    code: int
    stdout: str
    stderr: str
    data: dict  # check.json
    seconds: float
    out: Path  # the output folder

    def verdicts(self) -> dict[tuple[str, str, str], tuple[str, str | None]]:
        """(scene, feature, kind) -> (verdict, first finding's code or None)."""
        return {(c["scene"], c["feature"], c["kind"]):
                (c["verdict"], c["findings"][0]["code"] if c["findings"] else None)
                for c in self.data["cases"]}


def run_check(out: Path, renderer: str, scenes: list[Path], features: str,
              *extra: str, size: tuple[str, str] = SIZE) -> Checked:
    """The check in this process (the candidate still runs as a subprocess per case); asserts
    that neither the check nor the candidate printed a Python traceback."""
    argv = ["--renderer", renderer, *map(str, scenes), "--out", str(out), "--size", *size,
            "--features", features, "--quiet", *extra]
    stdout, stderr = io.StringIO(), io.StringIO()
    start = time.perf_counter()
    with redirect_stdout(stdout), redirect_stderr(stderr):
        code = check_main(argv)
    seconds = time.perf_counter() - start
    data = json.loads((out / "check.json").read_text(encoding="utf-8"))
    checked = Checked(code, stdout.getvalue(), stderr.getvalue(), data, seconds, out)
    assert "Traceback" not in checked.stdout + checked.stderr
    assert all("Traceback" not in (c["stderr_tail"] or "") for c in data["cases"])
    return checked


def corrupt(defect: str) -> str:
    return shlex.join([sys.executable, str(CORRUPT), defect])


# defect -> (scenes, --features, extra options): the fewest cases that show what it breaks
RUNS = {
    "no_shadows": ([MIRROR], "shadows,bounces,shadows+bounces", ()),
    "filter_2x": ([JITTER_FILTER], "plain,filter,jitter+filter", ()),
    "flip": ([SHADOWS], "plain", ()),
    "no_normals": ([SHADOWS], "plain", ()),
    "exit3": ([SHADOWS], "plain", ()),
    "sleep": ([SHADOWS], "plain", ("--timeout", "1")),
    "truncate": ([SHADOWS], "plain,shadows", ()),
    "double_size": ([SHADOWS], "plain", ()),
    "segv": ([SHADOWS], "plain", ()),
    "segv_filter": ([JITTER_FILTER], "plain,filter", ()),
    "segv_transformed": ([SHADOWS, MESH, MIRROR], "plain", ()),
    "no_output": ([SHADOWS], "plain", ()),
}


@pytest.fixture(scope="module")
def checked(tmp_path_factory):
    """defect -> its check, run once per module on first use."""
    done: dict[str, Checked] = {}

    def get(defect: str) -> Checked:
        if defect not in done:
            scenes, features, extra = RUNS[defect]
            out = tmp_path_factory.mktemp(f"check-{defect}")
            done[defect] = run_check(out, corrupt(defect), scenes, features, *extra)
        return done[defect]

    return get


def cases(scene: str, features: list[str]) -> list[tuple[str, str, str]]:
    return [(scene, f, k) for f in features for k in KINDS[f]]


def errors_everywhere(got: Checked, code: str, message: str, kinds=ALL_KINDS) -> None:
    """Every case of the run erred in every kind with exactly this one finding."""
    for c in got.data["cases"]:
        if c["kind"] in kinds:
            assert c["verdict"] == "error"
            assert c["findings"] == [{"code": code, "message": message.format(**c)}]
            assert c["failures"] == [f"{c['kind']}: {message.format(**c)}"]


# --- the perfect candidate ------------------------------------------------------------------
def test_python_m_tracer_as_a_subprocess_passes_every_case(tmp_path: Path):
    """`python -m raycheck.tracer` as the candidate passes every case and kind: exit 0, no
    fail/error."""
    got = run_check(tmp_path, shlex.join([sys.executable, "-m", "raycheck.tracer"]), [SHADOWS],
                    "plain,shadows,jitter,filter,jitter+filter")
    assert got.code == 0
    assert got.data["summary"] == {"pass": 13, "fail": 0, "error": 0}
    expected = cases("features/shadows", ["plain", "shadows", "jitter", "filter",
                                          "jitter+filter"])
    assert got.verdicts() == {c: ("pass", None) for c in expected}
    assert got.data["renderer"]["command"] == [sys.executable, "-m", "raycheck.tracer"]
    for c in got.data["cases"]:
        if c["jitter"]:  # judged against the reference's 64 realisations, all statistics pass
            assert c["jitter"]["realisations"] == 64
            assert all(s["passed"] for s in c["jitter"]["statistics"])
        else:
            assert (c["metrics"]["beyond_tolerance"], c["metrics"]["max_levels"]) == (0.0, 0)


# --- wrong images: fail exactly the cases the defect changes --------------------------------
def test_no_shadows_fails_exactly_the_shadow_cases(checked):
    """Dropping -shadows fails exactly the color image of every case with shadows, and the
    cause search names it: no shadow rays (the reference with shadow_missing reproduces it)."""
    got = checked("no_shadows")
    assert got.code == 1
    assert got.verdicts() == {
        ("course/spheres_mirror", "shadows", "color"): ("fail", "cause:shadow_missing"),
        ("course/spheres_mirror", "bounces4", "color"): ("pass", None),
        ("course/spheres_mirror", "shadows+bounces4", "color"): ("fail", "cause:shadow_missing"),
    }
    assert got.data["summary"] == {"pass": 1, "fail": 2, "error": 0}


def test_filter_twice_as_bright_fails_exactly_the_filtered_color_images(checked):
    """A doubled -filter color image fails filter and jitter+filter color, nothing else: the
    first with its kernel fitted, the second (twice as bright, which no mistake reproduces)
    with Renderer::Render's sampling first, where rendered without -jitter and -filter at
    three times the size the images match."""
    got = checked("filter_2x")
    assert got.code == 1
    expected = {c: ("pass", None) for c in cases("features/jitter_filter",
                                                 ["plain", "filter", "jitter+filter"])}
    expected[("features/jitter_filter", "filter", "color")] = ("fail", "filter_kernel")
    expected[("features/jitter_filter", "jitter+filter", "color")] = ("fail", "located")
    assert got.verdicts() == expected
    assert got.data["summary"] == {"pass": 7, "fail": 2, "error": 0}


def test_findings_are_shown_in_the_summary_the_case_page_and_the_overview(checked):
    """filter_2x's top finding: under its case in the terminal table, above the images on the
    case page with its evidence picture, in the overview cell's tooltip."""
    got = checked("filter_2x")
    entry = next(c for c in got.data["cases"] if (c["feature"], c["kind"]) == ("filter", "color"))
    message = entry["findings"][0]["message"]
    # every weight doubled: fitted on the reference's 3x render, within rounding
    assert entry["findings"][0]["code"] == "filter_kernel"
    assert message.startswith("Renderer::Render: your -filter weights are [2 4 2; 4 8 4; "
                              "2 4 2]/16, sum 2.00 (least squares on the reference rendered "
                              "at 3x without -filter, ")
    assert f"{'':<64}color: filter_kernel: {message}" in got.stdout.splitlines()
    case_page = (got.out / entry["page"]).read_text(encoding="utf-8")
    assert (f'<div class="findings"><b>Findings</b><ul><li><b>filter_kernel</b>: '
            f'{escape(message)}' in case_page)
    assert 'src="color_evidence.png"' in case_page
    assert (got.out / entry["page"]).parent.joinpath("color_evidence.png").is_file()
    index = (got.out / "index.html").read_text(encoding="utf-8")
    assert f"; finding filter_kernel: {escape(message)}\"" in index


def flip_changes(tmp_path: Path) -> dict[str, bool]:
    """Per kind of the plain shadows case: whether flipping the tracer's own 12x12 image
    changes more than the allowed share (0.5%) of pixels by more than one level."""
    names = {k: tmp_path / f"{k}.png" for k in ALL_KINDS}
    assert tracer_cli.main(["-input", str(SHADOWS), "-size", *SIZE, "-output",
                            str(names["color"]), "-normals", str(names["normals"]),
                            "-depth", "6", "14", str(names["depth"])]) == 0
    changes = {}
    for kind, path in names.items():
        a = np.asarray(Image.open(path).convert("RGB")).astype(int)
        beyond = np.abs(a - a[::-1]).max(axis=2) > 1
        changes[kind] = bool(beyond.mean() > 0.005)
    return changes


def test_flipped_rows_fail_every_image_flipping_changes(checked, tmp_path: Path):
    """Upside-down images fail every kind (the scene is not vertically symmetric)."""
    # the plain case fails exactly where flipping the tracer's image changes it
    assert flip_changes(tmp_path) == {"color": True, "normals": True, "depth": True}
    got = checked("flip")
    assert got.code == 1
    assert got.verdicts() == {c: ("fail", "flipped_vertical")
                              for c in cases("features/shadows", ["plain"])}
    assert got.data["summary"] == {"pass": 0, "fail": 3, "error": 0}


# --- a renderer that goes wrong: every image it owes is an error with the exact code --------
def test_missing_normals_file_errs_only_the_normals_image(checked):
    """No -normals file: plain normals is missing_output, led by where images are saved;
    color and depth are still judged."""
    got = checked("no_normals")
    assert got.code == 1
    assert got.verdicts() == {
        ("features/shadows", "plain", "color"): ("pass", None),
        ("features/shadows", "plain", "normals"): ("error", "located"),
        ("features/shadows", "plain", "depth"): ("pass", None),
    }
    normals = [c for c in got.data["cases"] if c["kind"] == "normals"]
    assert [c["findings"] for c in normals] == [[
        {"code": "located", "message": "Renderer::Render: your program gives no normals image "
         "of this case; the evidence points here: it exits with status 0 having written its "
         "color and depth images but not its normals image; the starter's Renderer::Render "
         "saves each image asked for after its pixel loop", "functions": ["Renderer::Render"]},
        {"code": "missing_output", "message": "normals.png was not written"}]]


def test_a_program_that_writes_no_image_is_led_to_where_images_are_saved(checked):
    """Exit status 0 and no image: every kind is missing_output, led by the saving at the end
    of Renderer::Render."""
    led_to_saving(checked("no_output"), {"code": "missing_output", "message": (
        "exited with status 0 but wrote none of its images (a course program does this when "
        "it cannot parse the scene)")},
        "it exits with status 0 without writing an image (a course program does so where its "
        "parser rejects the scene, which the reference's parsed); the starter's "
        "Renderer::Render saves each image asked for after its pixel loop")


def test_exit_status_3_errs_every_image(checked):
    """Exit status 3 after writing good images: every kind is exit_status, led by the saving
    at the end of Renderer::Render, where the images are written (the program chose to exit
    after it)."""
    led_to_saving(checked("exit3"), {"code": "exit_status", "message": "exited with status 3"},
                  "it exited with status 3 having written its color, normals and depth "
                  "images; the starter's Renderer::Render saves each image asked for after "
                  "its pixel loop, and nothing but the starter's code runs after it")


def led_to_saving(got: Checked, error: dict, evidence: str) -> None:
    """Every kind of the plain case errs with `error`, led by Renderer::Render's saving."""
    assert got.code == 1
    assert got.verdicts() == {c: ("error", "located")
                              for c in cases("features/shadows", ["plain"])}
    for c in got.data["cases"]:
        assert c["findings"] == [{"code": "located", "message": (
            "Renderer::Render: your program gives no image of this case; the evidence points "
            f"here: {evidence}"), "functions": ["Renderer::Render"]}, error]


def test_renderer_past_the_timeout_errs_every_image(checked):
    """A renderer sleeping past --timeout 1 is killed: every kind is timeout, in seconds."""
    got = checked("sleep")
    assert got.code == 1
    assert got.verdicts() == {c: ("error", "timeout")
                              for c in cases("features/shadows", ["plain"])}
    errors_everywhere(got, "timeout", "no result after 1 s (killed)")
    assert got.seconds < 10  # killed after 1 s, not after the wrapper's 60 s sleep


def test_truncated_png_errs_the_color_image_only(checked):
    """A color PNG cut to half its bytes is bad_png; normals and depth are still judged."""
    got = checked("truncate")
    assert got.code == 1
    assert got.verdicts() == {
        ("features/shadows", "plain", "color"): ("error", "bad_png"),
        ("features/shadows", "plain", "normals"): ("pass", None),
        ("features/shadows", "plain", "depth"): ("pass", None),
        ("features/shadows", "shadows", "color"): ("error", "bad_png"),
    }
    errors_everywhere(got, "bad_png", "out.png is not a readable PNG (image file is truncated)",
                      ("color",))


def test_image_of_twice_the_size_errs_every_image(checked):
    """Images of 2W x 2H: every kind is wrong_size, naming its file and both sizes."""
    got = checked("double_size")
    assert got.code == 1
    assert got.verdicts() == {c: ("error", "wrong_size")
                              for c in cases("features/shadows", ["plain"])}
    files = {"color": "out.png", "normals": "normals.png", "depth": "depth.png"}
    for kind, name in files.items():
        errors_everywhere(got, "wrong_size", f"{name} is 24x24, -size asked for 12x12", (kind,))


def test_sigsegv_is_a_crash(checked):
    """A renderer killed by SIGSEGV before writing: every kind is crash, naming the signal."""
    got = checked("segv")
    assert got.code == 1
    assert got.verdicts() == {c: ("error", "crash")
                              for c in cases("features/shadows", ["plain"])}
    errors_everywhere(got, "crash", "killed by signal SIGSEGV")


def test_a_crash_only_with_filter_points_at_renderer_render(checked):
    """A renderer killed by SIGSEGV with -filter only: its plain case passes; each kind of its
    -filter case leads with where the crash points (rendered without -filter at three times
    the size, every image matches the reference's: the -filter code is Renderer::Render's),
    then the crash."""
    got = checked("segv_filter")
    assert got.code == 1
    assert got.verdicts() == {
        **{c: ("pass", None) for c in cases("features/jitter_filter", ["plain"])},
        **{c: ("error", "located") for c in cases("features/jitter_filter", ["filter"])}}
    for c in got.data["cases"]:
        if c["feature"] == "filter":
            located, crash = c["findings"]
            assert located["message"].startswith(
                "Renderer::Render: your program gives no image of this case; the evidence "
                "points here: your program is killed by signal SIGSEGV only with -filter: "
                "rendered without it at three times the size (one ray at each sub-pixel "
                "position), its images match the reference's"), located
            assert crash == {"code": "crash", "message": "killed by signal SIGSEGV"}


def test_a_crash_on_the_scenes_with_transformed_objects_alone_points_at_transform(checked):
    """A renderer killed by SIGSEGV wherever the scene holds a transformed object: shadows.txt
    (a transformed cube mesh, a plane, spheres, a point and a directional light) crashes;
    cubemap_mesh.txt (a mesh, a plane, a sphere, a directional light) and spheres_mirror.txt
    (spheres, a plane, point lights) pass. Of the functions a student writes,
    Transform::intersect alone runs in the first and in neither of the others: each kind of
    the crashing case leads with it, then the crash."""
    got = checked("segv_transformed")
    assert got.code == 1
    assert got.verdicts() == {
        **{c: ("error", "located") for c in cases("features/shadows", ["plain"])},
        **{c: ("pass", None) for scene in ("course/cubemap_mesh", "course/spheres_mirror")
           for c in cases(scene, ["plain"])}}
    for c in got.data["cases"]:
        if c["scene"] == "features/shadows":
            located, crash = c["findings"]
            assert located == {"code": "located", "message": (
                "Transform::intersect: your program gives no image of this case; the evidence "
                "points here: it is killed by signal SIGSEGV on every case of the 1 scene "
                "holding transformed objects (features/shadows) and passes every case of the 2 "
                "scenes without (course/cubemap_mesh, course/spheres_mirror): of the starter "
                "functions, Transform::intersect alone runs in every scene it crashes on and "
                "in none it passes"), "functions": ["Transform::intersect"]}
            assert crash == {"code": "crash", "message": "killed by signal SIGSEGV"}


# --- process hygiene and the command line ---------------------------------------------------
def processes_naming(marker: str) -> list[int]:
    """Live (not zombie) processes with marker in their argv."""
    found = []
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit() or int(entry.name) == os.getpid():
            continue
        try:
            argv = (entry / "cmdline").read_bytes().decode("utf-8", "replace")
            state = (entry / "stat").read_text().rsplit(")", 1)[1].split()[0]
        except OSError:
            continue
        if marker in argv and state != "Z":
            found.append(int(entry.name))
    return found


def test_timed_out_renderer_leaves_no_process_behind(tmp_path: Path):
    """A renderer that started a child and then timed out leaves neither of them running."""
    pidfile = tmp_path / f"pids-{os.getpid()}-{time.time_ns()}.txt"  # also the argv marker
    renderer = shlex.join([sys.executable, str(ORPHAN), str(pidfile)])
    got = run_check(tmp_path / "out", renderer, [SHADOWS], "plain", "--timeout", "1")
    assert got.code == 1
    errors_everywhere(got, "timeout", "no result after 1 s (killed)")
    pids = [int(p) for p in pidfile.read_text().split()]  # both had started
    assert len(pids) == 2
    deadline = time.monotonic() + 2.0  # SIGKILL is asynchronous: give it a moment
    while processes_naming(str(pidfile)) and time.monotonic() < deadline:
        time.sleep(0.05)
    assert processes_naming(str(pidfile)) == []


def test_renderer_command_with_quotes_is_split_like_a_shell(tmp_path: Path):
    """A --renderer string with quotes runs the argv a POSIX shell would split it into."""
    # the script lies in a folder whose name has spaces and double quotes, single-quoted;
    # the defect is a double-quoted word
    folder = tmp_path / 'my "course" tracer'
    folder.mkdir()
    script = folder / "corrupt.py"
    shutil.copyfile(CORRUPT, script)
    for module in ("patched.py", "geometry_bugs.py"):  # the wrapper's own imports
        shutil.copyfile(CORRUPT.parent / module, folder / module)
    renderer = f"{shlex.quote(sys.executable)} '{script}' \"none\""
    got = run_check(tmp_path / "out", renderer, [SHADOWS], "plain")
    assert (got.code, got.stderr) == (0, "")
    data = got.data
    assert data["renderer"] == {"command": [sys.executable, str(script), "none"],
                                "sha256": hashlib.sha256(script.read_bytes()).hexdigest(),
                                "file": str(script), "sandbox": "none"}
    assert [(c["kind"], c["verdict"]) for c in data["cases"]] == \
        [("color", "pass"), ("normals", "pass"), ("depth", "pass")]


def test_a_cached_check_gives_the_uncached_check_json(tmp_path: Path, monkeypatch):
    """The disk cache (storage/disk_cache.py: the reference's renders, its distributions and their
    prepared statistics) changes no number: a defective candidate's check with every reference
    read from the cache has the check.json entries (verdicts, metrics, jitter statistics,
    findings) of its first, uncached run, and renders no reference. One deterministic and one
    jittered feature: each kind of cached entry, fewest candidate processes."""
    from raycheck.harness.pipeline import case

    monkeypatch.setenv("RAYCHECK_CACHE", str(tmp_path / "cache"))
    features = "filter,jitter+filter"
    first = run_check(tmp_path / "first", corrupt("filter_2x"), [JITTER_FILTER], features)
    reference_renders = []
    render_role = case.render_role

    def counted(renderer, *args, **kwargs):
        if renderer.name == "tracer":
            reference_renders.append(args)
        return render_role(renderer, *args, **kwargs)

    monkeypatch.setattr(case, "render_role", counted)
    second = run_check(tmp_path / "second", corrupt("filter_2x"), [JITTER_FILTER], features)
    assert reference_renders == []

    def numbers(checked: Checked) -> dict:
        keep = ("verdict", "metrics", "failures", "findings", "jitter")
        return {(c["scene"], c["feature"], c["kind"]): {k: c[k] for k in keep}
                for c in checked.data["cases"]}

    assert first.code == second.code == 1
    assert numbers(second) == numbers(first)
    assert {v for v, _ in first.verdicts().values()} == {"pass", "fail"}
    assert len(first.data["cases"]) == 6


def test_damaged_or_edited_cache_entries_are_made_again(tmp_path: Path, monkeypatch):
    """Every entry of the machine's cache (reference renders, distributions, prepared
    statistics) cut to a third of its rows, and every finished case's row.json replaced: the
    resumed check renders and judges again, with the first check's numbers, and no traceback
    (each of these ended a command in one once)."""
    monkeypatch.setenv("RAYCHECK_CACHE", str(tmp_path / "cache"))
    out = tmp_path / "out"
    first = run_check(out, "tracer", [SHADOWS], "plain,jitter")
    entries = list((tmp_path / "cache").rglob("*.npz"))
    assert {p.parent.name for p in entries} == {"cache", "renders", "prepared"}
    for path in entries:
        with np.load(path) as data:
            arrays = {k: v[: max(1, len(v) // 3)] if v.ndim > 1 else v for k, v in data.items()}
        np.savez(path, **arrays)
    rows = list((tmp_path / ".out.cache" / "results").glob("*/row.json"))
    assert len(rows) == 2
    for i, row in enumerate(rows):
        row.write_text(json.dumps({"row": 5, "command": []} if i else {"row": {}}))
    again = run_check(out, "tracer", [SHADOWS], "plain,jitter", "--resume")

    def numbers(checked: Checked) -> dict:
        return {(c["scene"], c["feature"], c["kind"]): (c["verdict"], c["metrics"], c["jitter"])
                for c in checked.data["cases"]}

    assert (first.code, again.code) == (0, 0)
    assert numbers(again) == numbers(first)


def test_the_scene_digest_of_the_cache_keys_follows_an_edited_asset(tmp_path: Path):
    """content_digest (every cache key's scene part) is kept per scene file only while the
    scene and the assets it reads are unchanged: an edited mesh gives the digest of its new
    bytes."""
    import os

    from raycheck.harness.storage.results import content_digest
    from raycheck.tracer.scene import load_scene
    from raycheck.tracer.scene.assets import scene_digest

    (tmp_path / "course").mkdir()
    shutil.copytree(REPO / "scenes" / "assets", tmp_path / "assets")
    scene = tmp_path / "course" / "smooth_mesh.txt"
    shutil.copy(REPO / "scenes" / "course" / "smooth_mesh.txt", scene)
    first = content_digest(scene)
    assert content_digest(scene) == first == scene_digest(scene, load_scene(scene))
    mesh = tmp_path / "assets" / "torus.obj"
    mesh.write_bytes(mesh.read_bytes() + b"# edited\n")
    os.utime(mesh, ns=(1, 1))  # a new time whatever the file system's resolution
    assert content_digest(scene) == scene_digest(scene, load_scene(scene)) != first


def test_the_tracer_keeps_a_scenes_parse_and_intersector_across_its_flag_sets(tmp_path: Path):
    """The in-process tracer renders a scene's flag sets with one parse and one intersector
    (BVH, octrees) per mode, and the images equal those of a renderer built afresh; an edited
    mesh is parsed and built again."""
    import os

    from raycheck.harness.renderers import TracerRenderer
    from raycheck.tracer.options import RenderOptions
    from raycheck.tracer.render import Renderer
    from raycheck.tracer.scene import load_scene
    from raycheck.tracer.scene.request import RenderRequest

    (tmp_path / "course").mkdir()
    shutil.copytree(REPO / "scenes" / "assets", tmp_path / "assets")
    scene = tmp_path / "course" / "smooth_mesh.txt"
    shutil.copy(REPO / "scenes" / "course" / "smooth_mesh.txt", scene)
    tracer, robust = TracerRenderer(), TracerRenderer(options={"mode": "robust"})
    requests = [RenderRequest(16, 12), RenderRequest(16, 12, shadows=True, bounces=2)]
    sessions = [tracer.open(scene, r) for r in requests]
    first, second = (s._renderer for s in sessions)
    assert second.isect is first.isect and second.scene is first.scene
    assert robust.open(scene, requests[0])._renderer.isect is not first.isect  # another mode
    for session, request in zip(sessions, requests):
        fresh = Renderer(load_scene(scene), RenderOptions(16, 12, shadows=request.shadows,
                                                          bounces=request.bounces)).render()
        assert np.array_equal(session.render().images["color"], fresh.color)
    mesh = tmp_path / "assets" / "torus.obj"
    mesh.write_bytes(mesh.read_bytes() + b"# edited\n")
    os.utime(mesh, ns=(1, 1))  # a new time whatever the file system's resolution
    assert tracer.open(scene, requests[0])._renderer.isect is not first.isect
