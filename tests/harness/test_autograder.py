"""Gradescope: results.json in the format Gradescope documents, from `raycheck check
--gradescope` and from `raycheck grade`; and the folder `raycheck autograder` writes, its
run_autograder run as Gradescope runs it (/autograder/submission in, /autograder/results/
results.json out) in a root of its own made with bubblewrap: the system's /usr, the folder,
and the raycheck that setup.sh would have installed (this checkout's; setup.sh itself needs
Gradescope's network and apt, and is not run here)."""
from __future__ import annotations

import json
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest
from gradescope_format import gradescope_problems
from test_grade_sources import NO_SHADOW_RAYS, write_program

from raycheck.harness.cli.autograder import main as autograder_main
from raycheck.harness.cli.check import main as check_main
from raycheck.harness.renderers.sandbox import ETC_PATHS, SYSTEM_PATHS

REPO = Path(__file__).resolve().parents[2]
SHADOWS = REPO / "scenes" / "features" / "shadows.txt"
def test_check_writes_gradescopes_results(tmp_path):
    """A renderer with one planted mistake: the shadows test fails and says which case, the
    plain one passes; the score is the sum of the tests'."""
    results = tmp_path / "results.json"
    renderer = f"{sys.executable} -m raycheck.tracer --mistake shadow_missing"
    code = check_main(["--renderer", renderer, str(SHADOWS), "--size", "12", "12",
                       "--features", "plain,shadows", "--out", str(tmp_path / "out"), "-j", "1",
                       "--quiet", "--gradescope", str(results)])
    assert code == 1
    data = json.loads(results.read_text())
    assert gradescope_problems(data) == []
    tests = {t["name"]: t for t in data["tests"]}
    assert {n: (t["score"], t["max_score"], t["status"]) for n, t in tests.items()} == {
        "plain": (20.0, 20.0, "passed"), "shadows": (0.0, 15.0, "failed")}
    assert data["score"] == 20.0
    assert tests["shadows"]["output"].startswith("0 of 1 cases pass\nfeatures/shadows shadows")
    assert "--mistake shadow_missing" in tests["shadows"]["output"]


def test_the_format_checker_finds_what_gradescope_would_refuse():
    good = {"score": 0.0, "output": "x", "tests": [{"name": "build", "score": 0.0,
                                                     "max_score": 0.0, "status": "failed",
                                                     "output": "", "visibility": "visible"}]}
    assert gradescope_problems(good) == []
    assert gradescope_problems({**good, "tests": [{"status": "error"}]}) == [
        "test 0: status error"]
    assert gradescope_problems({**good, "score": "20", "visibility": "students"}) == [
        "results: score is str", "results: visibility students"]


@pytest.mark.skipif(any(shutil.which(t) is None for t in ("bwrap", "cmake", "g++")),
                    reason="needs bwrap, cmake and g++")
def test_run_autograder_in_a_root_of_its_own(tmp_path):
    wheel = tmp_path / "raycheck-0.0-py3-none-any.whl"  # setup.sh is not run here
    with zipfile.ZipFile(wheel, "w") as z:
        z.writestr("raycheck/__init__.py", "")
    source = tmp_path / "source"
    assert autograder_main(["--out", str(source), "--scenes", str(SHADOWS), "--size", "12",
                            "12", "--features", "plain,shadows", "--wheel", str(wheel),
                            "--sandbox-read", str(REPO), "--sandbox-read",
                            sys.base_prefix]) == 0
    assert {p.name for p in source.iterdir()} == {"setup.sh", "run_autograder", wheel.name,
                                                  "scenes"}
    root = tmp_path / "autograder"
    shutil.copytree(source, root / "source")
    shutil.copyfile(source / "run_autograder", root / "run_autograder")
    (root / "run_autograder").chmod(0o755)
    write_program(root / "submission", (NO_SHADOW_RAYS,))
    (root / "results").mkdir()
    argv = ["bwrap", "--unshare-all", "--die-with-parent", "--proc", "/proc", "--dev", "/dev",
            "--tmpfs", "/tmp"]
    for name in (*SYSTEM_PATHS, *ETC_PATHS):
        path = Path(name)
        if path.is_symlink():
            argv += ["--symlink", str(path.readlink()), name]
        elif path.exists():
            argv += ["--ro-bind", name, name]
    for folder in (REPO, Path(sys.base_prefix)):
        argv += ["--ro-bind", str(folder), str(folder)]
    argv += ["--bind", str(root), "/autograder", "--clearenv", "--setenv", "PATH",
             "/usr/bin:/bin", "--setenv", "HOME", "/tmp", "--setenv", "RAYCHECK",
             str(Path(sys.executable).parent / "raycheck"), "--chdir", "/autograder", "--",
             "/autograder/run_autograder"]
    run = subprocess.run(argv, capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stdout + run.stderr
    data = json.loads((root / "results" / "results.json").read_text())
    assert gradescope_problems(data) == []
    assert data["score"] == 20.0, (data, run.stdout, run.stderr)
    assert [(t["name"], t["status"]) for t in data["tests"]] == [
        ("build", "passed"), ("plain", "passed"), ("shadows", "failed")]
