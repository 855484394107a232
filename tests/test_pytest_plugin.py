"""The pytest plugin (reports/pytest_plugin.py): `pytest --raycheck-renderer CMD` in a folder
without test files runs the check's cases as tests, one per case and image kind."""
from __future__ import annotations

import json
import shlex
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

pytest_plugins = ["pytester"]

SCENE = Path(__file__).resolve().parents[1] / "scenes" / "features" / "shadows.txt"
SMALL = ["--raycheck-scenes", str(SCENE), "--raycheck-size", "12", "12",
         "--raycheck-features", "plain,shadows"]
NO_SHADOWS = """\
import runpy, sys
sys.argv = [a for a in sys.argv if a != "-shadows"]
runpy.run_module("raycheck.tracer", run_name="__main__", alter_sys=True)
"""


@pytest.fixture
def folder(pytester: pytest.Pytester) -> pytest.Pytester:
    """An empty folder with an empty ini file (tox.ini)."""
    pytester.makeini("[pytest]\n")
    return pytester


def own_ini(pytester: pytest.Pytester) -> list[str]:
    """The folder's ini file and rootdir, not this project's pyproject.toml (the scene's path
    outside the folder would otherwise lead pytest there)."""
    return ["-c", str(pytester.path / "tox.ini")]


def run(pytester: pytest.Pytester, *args: str) -> tuple[pytest.RunResult, dict[str, str]]:
    """pytest with --junitxml in a subprocess (in process, pytester would unload numpy's
    extension modules between runs); returns the result and each test's JUnit outcome by name:
    passed, or the failure's message."""
    result = pytester.runpytest_subprocess(*own_ini(pytester), *args, "--junitxml", "junit.xml")
    outcomes = {}
    for case in ET.parse(pytester.path / "junit.xml").iter("testcase"):
        failure = case.find("failure")
        outcomes[case.get("name")] = "passed" if failure is None else failure.get("message")
    return result, outcomes


def test_reference_against_itself_passes_every_case_and_kind(folder: pytest.Pytester):
    renderer = f"{shlex.quote(sys.executable)} -m raycheck.tracer"
    _, outcomes = run(folder, "--raycheck-renderer", renderer, *SMALL)
    assert list(outcomes.items()) == [
        ("features/shadows/plain/color", "passed"), ("features/shadows/plain/normals", "passed"),
        ("features/shadows/plain/depth", "passed"), ("features/shadows/shadows/color", "passed")]


def test_ignored_flag_fails_its_kind_in_junit_and_results(folder: pytest.Pytester):
    """Renderer and results folder from the ini file, the rest from the command line."""
    wrapper = folder.path / "no_shadows.py"
    wrapper.write_text(NO_SHADOWS, encoding="utf-8")
    folder.makeini("[pytest]\nraycheck_renderer = "
                   f"{shlex.quote(sys.executable)} {shlex.quote(str(wrapper))}\n"
                   "raycheck_results = results\n")
    result, outcomes = run(folder, *SMALL)
    result.assert_outcomes(passed=3, failed=1)
    result.stdout.fnmatch_lines(["FAILED raycheck::features/shadows/shadows/color - color: *"])
    failed = {name: message for name, message in outcomes.items() if message != "passed"}
    assert list(failed) == ["features/shadows/shadows/color"]
    assert "of pixels differ" in failed["features/shadows/shadows/color"]

    results = folder.path / "results"
    check = json.loads((results / "check.json").read_text(encoding="utf-8"))
    assert check["summary"] == {"pass": 3, "fail": 1, "error": 0}
    assert (results / "index.html").is_file() and not (results / "junit.xml").exists()
    page = results / "cases" / "features_shadows" / "shadows" / "index.html"
    assert page.is_file() and f"page: {page}" in failed["features/shadows/shadows/color"]


def test_without_renderer_the_plugin_adds_nothing(folder: pytest.Pytester):
    folder.makepyfile("def test_own():\n    pass\n")
    result, outcomes = run(folder)
    assert outcomes == {"test_own": "passed"} and result.ret == 0
    assert not list(folder.path.glob("**/check.json"))
