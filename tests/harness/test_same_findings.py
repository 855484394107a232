"""Findings are a function of the submission: a real program with two mistakes (the C++
solution with its shadow rays started on the surface, not 0.01 off it, and its point lights
falling off with d instead of d^2) gets the same check.json, times aside, whether its cases
run in one process, in a pool of two, in a Dask cluster on loopback, in another order, or
resumed after some of them were lost. Its jittered cases' causes come from the same scene's
unjittered ones (their priors), which run first wherever the cases run."""
from __future__ import annotations

import shutil
from pathlib import Path

import pytest
from solution import Edit, build_solution, copy_solution
from test_parallel import quietly, without_times

from raycheck.harness.cli.check import main as check_main

REPO = Path(__file__).resolve().parents[2]
SCENES = ("features/shadows", "course/spheres_mirror")
TWO_MISTAKES = (
    Edit("src/Renderer.cpp", "Ray shadowRay(p + 0.01f * tolight, tolight);",
         "Ray shadowRay(p, tolight);"),
    Edit("src/Light.cpp", "intensity = _color / ((distToLight * _falloff) * distToLight);",
         "intensity = _color / (distToLight * _falloff);"),
)
NEEDS = [t for t in ("cmake", "g++") if shutil.which(t) is None]
pytestmark = pytest.mark.skipif(bool(NEEDS), reason=f"not installed: {', '.join(NEEDS)}")


def argv(program: Path, out: Path, scenes=SCENES, *extra: str) -> list[str]:
    return ["--renderer", str(program), *scenes, "--out", str(out), "--size", "24", "24",
            "--features", "plain,shadows,jitter", "--quiet", *extra]


@pytest.fixture(scope="module")
def program(tmp_path_factory) -> Path:
    return build_solution(copy_solution(tmp_path_factory.mktemp("two") / "src", TWO_MISTAKES))


@pytest.fixture(scope="module")
def serial(program: Path, tmp_path_factory) -> tuple[Path, dict]:
    """The check in one process: its folder and check.json."""
    out = tmp_path_factory.mktemp("serial") / "out"
    assert quietly(check_main, argv(program, out, SCENES, "-j", "1")) == 1
    return out, without_times(out / "check.json")


def by_case(report: dict) -> dict:
    return {(c["scene"], c["feature"], c["kind"]): (c["verdict"], c["findings"])
            for c in report["cases"]}


def test_the_two_mistakes_are_named_and_jittered_cases_use_them(serial):
    _, report = serial
    named = {f["code"] for c in report["cases"] if c["verdict"] == "fail"
             for f in c["findings"][:1]}
    assert {"cause:shadow_offset", "cause:falloff_power"} <= named
    jittered = [c for c in report["cases"] if c["feature"] == "jitter" and c["verdict"] == "fail"]
    assert jittered and all(c["findings"][0]["code"] == "cause:falloff_power"
                            for c in jittered)


def test_a_pool_gives_the_same_findings(program: Path, serial, tmp_path):
    _, report = serial
    assert quietly(check_main, argv(program, tmp_path / "pool", SCENES, "-j", "2")) == 1
    assert without_times(tmp_path / "pool" / "check.json") == report


@pytest.mark.full  # about 8 s
def test_another_order_gives_the_same_findings(program: Path, serial, tmp_path):
    _, report = serial
    assert quietly(check_main, argv(program, tmp_path / "reversed", SCENES[::-1], "-j", "2")) == 1
    assert by_case(without_times(tmp_path / "reversed" / "check.json")) == by_case(report)


def test_a_resumed_check_gives_the_same_findings(program: Path, serial, tmp_path):
    """The results of a finished check, some of them lost as an interrupt loses the cases
    still running (an unjittered case's among them), then --resume: the lost ones run again,
    the jittered ones with the same priors."""
    out, report = serial
    copy = tmp_path / "out"
    shutil.copytree(out.parent / ".out.cache", tmp_path / ".out.cache")
    results = sorted(p for p in (tmp_path / ".out.cache" / "results").iterdir()
                     if p.name[0] != ".")
    for lost in results[::2]:
        shutil.rmtree(lost)
    assert quietly(check_main, argv(program, copy, SCENES, "-j", "1", "--resume")) == 1
    assert without_times(copy / "check.json") == report


@pytest.mark.full  # about 10 s: the cluster's start and its workers' imports
def test_a_dask_cluster_gives_the_same_findings(program: Path, serial, tmp_path):
    from distributed import LocalCluster

    _, report = serial
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                      dashboard_address=None, protocol="tcp") as cluster:
        code = quietly(check_main, argv(program, tmp_path / "out", SCENES, "--scheduler",
                                        cluster.scheduler_address))
    assert code == 1
    assert without_times(tmp_path / "out" / "check.json") == report
