"""The pytest plugin (harness/pytest_plugin.py): `pytest --raycheck-renderer CMD` in a folder
without test files runs the check's cases as tests, one per case and image kind."""
from __future__ import annotations

import json
import os
import shlex
import subprocess
import sys
import time
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Iterator

import pytest

SCENE = Path(__file__).resolve().parents[2] / "scenes" / "features" / "shadows.txt"
SMALL = ["--raycheck-scenes", str(SCENE), "--raycheck-size", "12", "12",
         "--raycheck-features", "plain,shadows"]
NO_SHADOWS = """\
import runpy, sys
sys.argv = [a for a in sys.argv if a != "-shadows"]
runpy.run_module("raycheck.tracer", run_name="__main__", alter_sys=True)
"""
# each run gets a HOME of its own (as pytester's do: no user configuration), where Dr.Jit would
# keep a kernel cache of its own and compile every kernel afresh; they share ours instead
KERNEL_CACHE = os.environ.get("DRJIT_CACHE_DIR") or str(Path.home() / ".drjit")


@dataclass
class PluginRun:
    """`pytest --junitxml junit.xml ARGS` in a folder of its own and in a subprocess (in
    process, pytester would unload numpy's extension modules between runs)."""
    folder: Path
    proc: subprocess.Popen
    started: float

    @classmethod
    def start(cls, folder: Path, args: list[str]) -> PluginRun:
        """Starts the run; its own ini file (tox.ini) and rootdir, not this project's
        pyproject.toml (the scene's path outside the folder would otherwise lead pytest
        there)."""
        env = dict(os.environ, HOME=str(folder), PY_COLORS="0", DRJIT_CACHE_DIR=KERNEL_CACHE)
        env.pop("PYTEST_ADDOPTS", None)
        # a course's CI has no Hypothesis; this environment's plugin imports all of it (~1 s
        # of CPU) at the end of every run, tests of its own or not
        with open(folder / "stdout.txt", "wb") as out, open(folder / "stderr.txt", "wb") as err:
            proc = subprocess.Popen(
                [sys.executable, "-m", "pytest", "-p", "no:hypothesispytest",
                 f"--basetemp={folder / 'basetemp'}", "-c", str(folder / "tox.ini"), *args,
                 "--junitxml", "junit.xml"],
                cwd=folder, env=env, stdin=subprocess.DEVNULL, stdout=out, stderr=err)
        return cls(folder, proc, time.perf_counter())

    def wait(self) -> tuple[pytest.RunResult, dict[str, str]]:
        """The result and each test's JUnit outcome by name: passed, or the failure's
        message."""
        code = self.proc.wait(timeout=600)
        lines = [(self.folder / name).read_text().splitlines()
                 for name in ("stdout.txt", "stderr.txt")]
        result = pytest.RunResult(code, *lines, time.perf_counter() - self.started)
        outcomes = {}
        for case in ET.parse(self.folder / "junit.xml").iter("testcase"):
            failure = case.find("failure")
            outcomes[case.get("name")] = "passed" if failure is None else failure.get("message")
        return result, outcomes


def reference_against_itself(folder: Path) -> list[str]:
    (folder / "tox.ini").write_text("[pytest]\n")
    return ["--raycheck-renderer", f"{shlex.quote(sys.executable)} -m raycheck.tracer", *SMALL]


def ignored_flag(folder: Path) -> list[str]:
    """Renderer and results folder from the ini file, the rest from the command line."""
    wrapper = folder / "no_shadows.py"
    wrapper.write_text(NO_SHADOWS, encoding="utf-8")
    (folder / "tox.ini").write_text("[pytest]\nraycheck_renderer = "
                                    f"{shlex.quote(sys.executable)} {shlex.quote(str(wrapper))}\n"
                                    "raycheck_results = results\n")
    return SMALL


# the folder's own test: the plugin, loaded in every run, imported nothing of the harness
OWN_TEST = """\
import sys

def test_own():
    loaded = [m for m in sys.modules if m == "numpy" or m.startswith("raycheck.")]
    assert sorted(loaded) == ["raycheck.harness", "raycheck.harness.check_options",
                              "raycheck.harness.pytest_plugin"]
"""


def without_renderer(folder: Path) -> list[str]:
    (folder / "tox.ini").write_text("[pytest]\n")
    (folder / "test_own.py").write_text(OWN_TEST)
    return []


# test name -> how its run's folder is set up, and the run's arguments
RUNS: dict[str, Callable[[Path], list[str]]] = {
    "test_reference_against_itself_passes_every_case_and_kind": reference_against_itself,
    "test_ignored_flag_fails_its_kind_in_junit_and_results": ignored_flag,
    "test_without_renderer_the_plugin_adds_nothing": without_renderer,
}


@pytest.fixture(scope="module")
def runs(request: pytest.FixtureRequest,
         tmp_path_factory: pytest.TempPathFactory) -> Iterator[dict[str, PluginRun]]:
    """The runs of the selected tests, all started at once: each is a fresh interpreter whose
    start-up is most of its time, and together they keep both cores busy."""
    selected = {item.name for item in request.session.items if item.module is request.module}
    started = {}
    for name, setup in RUNS.items():
        if name in selected:
            folder = tmp_path_factory.mktemp(name.removeprefix("test_")[:30])
            started[name] = PluginRun.start(folder, setup(folder))
    yield started
    for run in started.values():  # a test that failed before waiting leaves none behind
        if run.proc.poll() is None:
            run.proc.kill()
            run.proc.wait()


@pytest.fixture
def run(runs: dict[str, PluginRun], request: pytest.FixtureRequest) -> PluginRun:
    """This test's run."""
    return runs[request.node.name]


def test_reference_against_itself_passes_every_case_and_kind(run: PluginRun):
    _, outcomes = run.wait()
    assert list(outcomes.items()) == [
        ("features/shadows/plain/color", "passed"), ("features/shadows/plain/normals", "passed"),
        ("features/shadows/plain/depth", "passed"), ("features/shadows/shadows/color", "passed")]


def test_ignored_flag_fails_its_kind_in_junit_and_results(run: PluginRun):
    result, outcomes = run.wait()
    result.assert_outcomes(passed=3, failed=1)
    result.stdout.fnmatch_lines(["FAILED raycheck::features/shadows/shadows/color - color: *"])
    failed = {name: message for name, message in outcomes.items() if message != "passed"}
    assert list(failed) == ["features/shadows/shadows/color"]
    assert "of pixels differ" in failed["features/shadows/shadows/color"]

    results = run.folder / "results"
    check = json.loads((results / "check.json").read_text(encoding="utf-8"))
    assert check["summary"] == {"pass": 3, "fail": 1, "error": 0}
    assert (results / "index.html").is_file() and not (results / "junit.xml").exists()
    page = results / "cases" / "features_shadows" / "shadows" / "index.html"
    assert page.is_file() and f"page: {page}" in failed["features/shadows/shadows/color"]


def test_without_renderer_the_plugin_adds_nothing(run: PluginRun):
    result, outcomes = run.wait()
    assert outcomes == {"test_own": "passed"} and result.ret == 0
    assert not list(run.folder.glob("**/check.json"))


def test_a_bad_cache_size_is_a_usage_error(tmp_path: Path):
    (tmp_path / "tox.ini").write_text("[pytest]\n")
    env = dict(os.environ, HOME=str(tmp_path), RAYCHECK_CACHE_SIZE="2 gigs")
    env.pop("PYTEST_ADDOPTS", None)
    proc = subprocess.run([sys.executable, "-m", "pytest", "-p", "no:hypothesispytest", "-c",
                           str(tmp_path / "tox.ini"), "--raycheck-renderer", "tracer", *SMALL],
                          cwd=tmp_path, env=env, capture_output=True, text=True, timeout=120)
    assert proc.returncode == pytest.ExitCode.USAGE_ERROR
    assert ("ERROR: raycheck: RAYCHECK_CACHE_SIZE='2 gigs' is not a size (a whole number of "
            "bytes, or of K, M, G or T: 500M, 2G)") in proc.stderr


@pytest.mark.parametrize("options, message", [
    (["--raycheck-features", "shadowz"], "ERROR: raycheck: --raycheck-features: unknown shadowz"),
    (["--raycheck-size", "0", "12"],
     "ERROR: raycheck: --raycheck-size: expected W H, two integers >= 1, found 0 12"),
    (["--raycheck-reference", "embree"],
     "ERROR: raycheck: --raycheck-reference: expected one of mitsuba, tracer, found embree"),
])
def test_a_bad_setting_is_a_usage_error_naming_the_plugins_option(tmp_path: Path, options,
                                                                   message):
    """The check's own validation (check_config.CheckConfig) names the option as the plugin
    spells it, not as `raycheck check` does."""
    (tmp_path / "tox.ini").write_text("[pytest]\n")
    env = dict(os.environ, HOME=str(tmp_path))
    env.pop("PYTEST_ADDOPTS", None)
    proc = subprocess.run([sys.executable, "-m", "pytest", "-p", "no:hypothesispytest", "-c",
                           str(tmp_path / "tox.ini"), "--raycheck-renderer", "tracer",
                           "--raycheck-scenes", str(SCENE), *options],
                          cwd=tmp_path, env=env, capture_output=True, text=True, timeout=120)
    assert proc.returncode == pytest.ExitCode.USAGE_ERROR, proc.stderr
    assert message in proc.stderr and "Traceback" not in proc.stderr, proc.stderr
