"""Where cases run does not change what they give: `check` of the tracer with -j 1 (in
process), -j 2 (a spawn process pool) and --scheduler (a real Dask cluster of two worker
processes on 127.0.0.1) writes the same check.json, times aside; a check killed with SIGKILL
midway and rerun with --resume keeps every finished case and renders only the missing ones
(the candidate tests/wrappers/counting.py logs each invocation); `grade` of wrapper
submissions gives the expected class table. 12x12, one scene, few features."""
from __future__ import annotations

import csv
import io
import json
import os
import shlex
import signal
import subprocess
import sys
import time
from contextlib import redirect_stderr, redirect_stdout
from pathlib import Path

import numpy as np
import pytest

from raycheck.harness.cli.check import main as check_main
from raycheck.harness.cli.grade import main as grade_main

REPO = Path(__file__).resolve().parents[2]
WRAPPERS = REPO / "tests" / "wrappers"
SHADOWS = REPO / "scenes" / "features" / "shadows.txt"
FEATURES = "plain,shadows,jitter"
N_CASES = 3


def counting(log: Path) -> str:
    return shlex.join([sys.executable, str(WRAPPERS / "counting.py"), f"--log={log}"])


def check_argv(renderer: str, out: Path, *extra: str) -> list[str]:
    return ["--renderer", renderer, str(SHADOWS), "--out", str(out), "--size", "12", "12",
            "--features", FEATURES, "--quiet", *extra]


def quietly(main, argv: list[str]) -> int:
    with redirect_stdout(io.StringIO()), redirect_stderr(io.StringIO()) as err:
        code = main(argv)
    assert "Traceback" not in err.getvalue()
    return code


def renders(log: Path) -> int:
    return len(log.read_text().splitlines()) if log.exists() else 0


def without_times(path: Path) -> dict:
    data = json.loads(path.read_text(encoding="utf-8"))
    del data["seconds"], data["provenance"]
    for case in data["cases"]:
        del case["seconds"]
    return data


@pytest.fixture(scope="module")
def serial(tmp_path_factory) -> dict:
    """check.json of the tracer with -j 1."""
    out = tmp_path_factory.mktemp("serial") / "out"
    assert quietly(check_main, check_argv("tracer", out, "-j", "1")) == 0
    return without_times(out / "check.json")


def test_a_local_pool_gives_the_same_check_as_one_process(serial, tmp_path: Path):
    assert quietly(check_main, check_argv("tracer", tmp_path / "out", "-j", "2")) == 0
    assert without_times(tmp_path / "out" / "check.json") == serial


@pytest.mark.full  # about 10 s: the cluster's start and its workers' imports
def test_a_dask_cluster_gives_the_same_check_as_one_process(serial, tmp_path: Path):
    from distributed import LocalCluster

    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                      dashboard_address=None, protocol="tcp") as cluster:
        code = quietly(check_main, check_argv("tracer", tmp_path / "out", "--scheduler",
                                              cluster.scheduler_address))
    assert code == 0
    assert without_times(tmp_path / "out" / "check.json") == serial


def test_resume_after_kill_9_renders_only_the_missing_cases(tmp_path: Path):
    log = tmp_path / "renders.log"
    candidate = counting(log)
    out = tmp_path / "out"
    cache = tmp_path / ".out.cache" / "results"
    cli = "import sys; from raycheck.harness.cli import main; sys.exit(main())"
    proc = subprocess.Popen([sys.executable, "-c", cli, "check",
                             *check_argv(candidate, out, "-j", "1")],
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                            start_new_session=True)
    try:  # killed once a case is stored, while the next one renders
        deadline = time.monotonic() + 60
        while not (cache.is_dir() and any(p.name[0] != "." for p in cache.iterdir())):
            assert proc.poll() is None and time.monotonic() < deadline
            time.sleep(0.02)
    finally:
        os.killpg(proc.pid, signal.SIGKILL)  # the check; its candidate has its own group
        proc.wait()
    from test_check import processes_naming

    # the orphaned candidate logs its render, then ends; gone for a whole second, as a process
    # that execs is briefly without a command line to find
    deadline, gone_since = time.monotonic() + 60, time.monotonic()
    while time.monotonic() - gone_since < 1.0:
        if processes_naming(str(log)):
            gone_since = time.monotonic()
        assert time.monotonic() < deadline
        time.sleep(0.02)
    assert not out.exists()  # nothing half-written where the report goes
    finished = [p for p in cache.iterdir() if p.name[0] != "."]
    assert 1 <= len(finished) < N_CASES
    before = renders(log)
    assert quietly(check_main, check_argv(candidate, out, "-j", "1", "--resume")) == 0
    assert renders(log) - before == N_CASES - len(finished)
    assert not list(tmp_path.glob(".out.new-*"))  # the killed run's staging folder is gone
    resumed = without_times(out / "check.json")
    before = renders(log)
    assert quietly(check_main, check_argv(candidate, out, "-j", "1")) == 0  # all afresh
    assert renders(log) - before == N_CASES
    assert without_times(out / "check.json") == resumed


def submission(folder: Path, defect: str) -> Path:
    """A folder holding an executable a2 that runs corrupt.py DEFECT."""
    folder.mkdir()
    a2 = folder / "a2"
    a2.write_text(f"#!/bin/sh\nexec {shlex.join([sys.executable, str(WRAPPERS / 'corrupt.py')])}"
                  f" {defect} \"$@\"\n")
    a2.chmod(0o755)
    return folder


# name, corrupt.py defect, row of the class table: (score, shadows passed, filter passed,
# crashes, timeouts)
SUBMISSIONS = [
    ("perfect", "none", (8.0, "1", "1", "0", "0")),
    ("no_shadows", "no_shadows", (5.0, "0", "1", "0", "0")),
    ("crashes", "segv", (0.0, "0", "0", "2", "0")),
    ("hangs", "sleep", (0.0, "0", "0", "0", "2")),
    ("bright", "filter_2x", (3.0, "1", "0", "0", "0")),
]
# The hanging submission's two 4 s timeouts were most of this test's time: the full run only.
# The quick run still grades a crashing row (errors score nothing and are counted), and
# test_check.py's timeout tests show that a renderer past the timeout errs its images.
QUICK_LEAVES_OUT = {"hangs"}
# the wrappers run the tracer of this checkout (its venv, its kernel cache): outside the
# sandbox, which test_sandbox.py and test_grade_sources.py try
OUTSIDE_THE_SANDBOX = ("--sandbox", "off")


def test_grade_wrapper_submissions(tmp_path: Path, full_run: bool, monkeypatch):
    """Perfect, no shadows, crashing, hanging (full run) and a twice-as-bright filter: each row
    passes exactly what its defect leaves alone; the hanging one costs its timeouts, not the
    class."""
    # a machine cache of its own: other tests' reference renders of these cases are in the
    # session's, and one found there never reaches the class's render cache counted below
    monkeypatch.setenv("RAYCHECK_CACHE", str(tmp_path / "machine-cache"))
    chosen = [s for s in SUBMISSIONS if full_run or s[0] not in QUICK_LEAVES_OUT]
    subs = [submission(tmp_path / name, defect) for name, defect, _ in chosen]
    weights = tmp_path / "weights.toml"
    weights.write_text("[points]\nshadows = 3\nfilter = 5\n")
    out = tmp_path / "class"
    start = time.perf_counter()
    assert quietly(grade_main, [*map(str, subs), "--scenes", str(SHADOWS), "--size", "12", "12",
                                "--features", "shadows,filter", "--timeout", "4",
                                "--weights", str(weights), "--out", str(out), "-j", "2",
                                *OUTSIDE_THE_SANDBOX]) == 0
    assert time.perf_counter() - start < 60  # two 4 s timeouts, not a minute per case
    rows = {r["name"]: r for r in csv.DictReader(io.StringIO((out / "grades.csv").read_text()))}
    table = {name: (float(r["score"]), r["shadows passed"], r["filter passed"], r["crashes"],
                    r["timeouts"]) for name, r in rows.items()}
    assert table == {name: row for name, _, row in chosen}
    assert json.loads((out / "grades.json").read_text())["submissions"][0]["max_score"] == 8
    for name in rows:
        check = json.loads((out / name / "check.json").read_text())
        assert len({(c["scene"], c["feature"]) for c in check["cases"]}) == 2
        assert f'href="{name}/index.html"' in (out / "index.html").read_text()
    # the reference of each case rendered once for the class (2 cases, 1 render each), and the
    # reference renders that the findings of failing cases need (the doubled filter's without
    # -filter, and at 3x without it for its kernel: 2; no_shadows is named by the cause search,
    # which renders in process, uncached), each once, whatever the number of submissions
    assert len(list((tmp_path / ".class.cache" / "renders").glob("*.npz"))) == 2 + 2


def test_grade_judges_jittered_cases_by_the_references_distribution(tmp_path: Path,
                                                                      monkeypatch):
    """A jittered case: the reference's K realisations come from one reseeded session, are
    kept as one distribution in the machine's cache, and none of them lands in the class's
    render cache, which holds the case's one reference render. (The statistical test's
    false-alarm rate is 1e-3 an image; the seeds are fixed, so the verdict is too.)"""
    monkeypatch.setenv("RAYCHECK_CACHE", str(tmp_path / "machine-cache"))
    sub = submission(tmp_path / "perfect", "none")
    out = tmp_path / "class"
    assert quietly(grade_main, [str(sub), "--scenes", str(SHADOWS), "--size", "12", "12",
                                "--features", "jitter", "--out", str(out), "-j", "1",
                                *OUTSIDE_THE_SANDBOX]) == 0
    row = next(csv.DictReader(io.StringIO((out / "grades.csv").read_text())))
    assert (row["jitter passed"], row["jitter total"], row["errors"]) == ("1", "1", "0")
    renders = list((tmp_path / ".class.cache" / "renders").glob("*.npz"))
    assert len(renders) == 1
    assert len(list((tmp_path / "machine-cache").glob("*.npz"))) == 1  # the distribution
    # a class render cut short (an edited or damaged entry) is rendered again, the grade the
    # same (it ended the command in a traceback once)
    with np.load(renders[0]) as data:
        np.savez(renders[0], **{k: v[:3] for k, v in data.items() if v.ndim}, _seconds=1.0)
    assert quietly(grade_main, [str(sub), "--scenes", str(SHADOWS), "--size", "12", "12",
                                "--features", "jitter", "--out", str(out), "-j", "1",
                                *OUTSIDE_THE_SANDBOX]) == 0
    assert next(csv.DictReader(io.StringIO((out / "grades.csv").read_text()))) == row


def test_a_stopped_pool_has_closed_the_pipe_pythons_exit_hook_writes_to():
    """WorkerPool.stop() returns only once the pool's manager thread has ended and closed its
    wake-up pipe: Python's exit hook writes to that pipe without a lock, so a pipe closed
    while the interpreter exits makes the write fail with a traceback after "interrupted"."""
    from raycheck.harness.pipeline.executor import WorkerPool

    pool = WorkerPool(2)
    future = pool.submit(time.sleep, 60)
    deadline = time.monotonic() + 60
    while not future.running() and time.monotonic() < deadline:
        time.sleep(0.05)
    assert future.running()
    manager = pool._executor_manager_thread
    wakeup = pool._executor_manager_thread_wakeup
    pool.stop()
    assert manager is not None and not manager.is_alive()
    assert wakeup._closed
