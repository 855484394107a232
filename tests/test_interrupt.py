"""Ctrl-C stops a command between two kernel launches (each bounded in work), cleans up and
exits with status 130: no output file of the render, no half-built output folder, and the
previous one as it was."""
from __future__ import annotations

import json
import os
import shlex
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from raycheck.harness.cli import main as raycheck_main

REPO = Path(__file__).resolve().parent.parent
FALLOFF = REPO / "scenes" / "features" / "falloff.txt"
WRAPPERS = Path(__file__).resolve().parent / "wrappers"
GRACE_S = 3.0  # a launch is ~0.5-1 s on an idle core; room for a loaded CI machine


@pytest.fixture(autouse=True)
def _ctrl_c_reaches_the_commands():
    """The commands start with Ctrl-C's default disposition, as from a terminal, even where
    this run ignores SIGINT (a script's background job): an ignored signal stays ignored across
    exec, Python then installs no KeyboardInterrupt handler, and the command renders on."""
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    yield
    signal.signal(signal.SIGINT, previous)


def _interrupt_when(proc: subprocess.Popen, marker: str, stream) -> float:
    """Sends SIGINT once `marker` appears on the stream; returns the seconds to exit."""
    for line in stream:
        if marker in line:
            break
    proc.send_signal(signal.SIGINT)
    sent = time.perf_counter()
    proc.wait(timeout=60)
    return time.perf_counter() - sent


def test_ctrl_c_stops_a_long_render_between_launches(tmp_path):
    out = tmp_path / "a.png"
    # 256^2 pixels x 4096 samples x 3 levels x 3 rays: ~2.4e9 ray casts, seconds of work past
    # the first progress line
    proc = subprocess.Popen(
        [sys.executable, "-m", "raycheck.tracer", "-input", str(FALLOFF), "-size", "256", "256",
         "-jitter", "--samples", "4096", "-bounces", "2", "-shadows", "-output", str(out)],
        stderr=subprocess.PIPE, stdin=subprocess.DEVNULL, text=True)
    seconds = _interrupt_when(proc, "rendering:", proc.stderr)  # past compiling, launching
    rest = proc.stderr.read()
    assert proc.returncode == 130 and "interrupted" in rest, rest
    assert seconds < GRACE_S, seconds
    assert list(tmp_path.iterdir()) == []  # no image, no temporary file


def check_argv(out: Path) -> list[str]:
    return ["check", "--renderer", "tracer", str(FALLOFF), "--out", str(out)]


def test_ctrl_c_in_a_check_keeps_the_previous_folder(tmp_path, capsys):
    out = tmp_path / "check"
    base = [sys.executable, "-m", "raycheck.harness", *check_argv(out)]
    # the previous folder, written in this process (a fresh one would add its start-up)
    assert raycheck_main(check_argv(out) + ["--size", "4", "4", "--features", "plain",
                                            "--quiet"]) == 0
    before = sorted(p.relative_to(out) for p in out.rglob("*"))
    env = dict(os.environ, PYTHONUNBUFFERED="1")
    proc = subprocess.Popen(base + ["--size", "96", "96"], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, stdin=subprocess.DEVNULL, text=True,
                            env=env)
    seconds = _interrupt_when(proc, "[1/", proc.stdout)  # the first case is done
    err = proc.stderr.read()
    assert proc.returncode == 130 and "interrupted" in err, err
    assert seconds < GRACE_S + 2, seconds
    assert sorted(p.relative_to(out) for p in out.rglob("*")) == before
    assert [p.name for p in tmp_path.iterdir() if ".new-" in p.name] == []


def test_a_second_writer_of_one_folder_is_refused(tmp_path, capsys):
    """While one check writes a folder, another into the same folder stops at once (exit 2,
    one line) and leaves the first's run alone. (The second runs in this process: the lock is
    the folder's, whatever process holds it.)"""
    out, gate = tmp_path / "check", tmp_path / "go"
    # a candidate whose second case waits for the gate: the first run is certainly still
    # writing when the second starts, however fast the renders
    holding = shlex.join([sys.executable, str(WRAPPERS / "holding.py"),
                          f"--log={tmp_path / 'log'}", f"--gate={gate}"])
    argv = ["check", "--renderer", holding, str(FALLOFF), "--out", str(out)]
    env = dict(os.environ, PYTHONUNBUFFERED="1")
    # three deterministic cases (the jittered ones, with their reference distributions, would
    # only lengthen the wait for its end)
    first = subprocess.Popen([sys.executable, "-m", "raycheck.harness", *argv, "--size", "64",
                              "64", "--features", "shadows,plain,filter", "-j", "1"],
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                             stdin=subprocess.DEVNULL, text=True, env=env)
    for line in first.stdout:  # the first case is done: the folder is being written
        if "[1/" in line:
            break
    capsys.readouterr()
    second = raycheck_main(check_argv(out) + ["--size", "8", "8", "--quiet"])
    second_err = capsys.readouterr().err
    gate.touch()
    first.stdout.read()
    assert first.wait(timeout=300) == 0
    assert second == 2 and second_err.count("\n") == 1, second_err
    assert "another raycheck run is writing this folder" in second_err
    cases = json.loads((out / "check.json").read_text())["cases"]
    assert cases and {tuple(c["size"]) for c in cases} == {(64, 64)}  # the first run's alone


@pytest.mark.full  # four reports: 15 s
def test_kill_9_at_random_points_of_a_report_keeps_the_previous_one(tmp_path):
    """A report killed with SIGKILL anywhere (seeded random moments, from start-up to the
    last case) leaves the previous report as it was, byte for byte: the new one was only ever
    written in a staging folder beside it, which the next run removes. (A run that finished
    before its moment came replaced the report whole: the same files, new numbers.)"""
    import random

    out = tmp_path / "out"
    base = [sys.executable, "-m", "raycheck.harness", "report", str(FALLOFF), "--out",
            str(out), "--size", "8", "--no-sweeps", "--quiet", "-j", "1"]
    # the first run fills the render caches ($RAYCHECK_CACHE): the killed runs take as long
    # as the second
    subprocess.run(base, check=True, capture_output=True, timeout=300)
    start = time.perf_counter()
    subprocess.run(base, check=True, capture_output=True, timeout=300)
    run_s = time.perf_counter() - start
    before = {p.relative_to(out): p.read_bytes() for p in (out / "report").rglob("*")
              if p.is_file()}
    rng = random.Random(16)
    killed = 0
    for delay in sorted(rng.uniform(0.1, 0.8) * run_s for _ in range(4)):
        proc = subprocess.Popen(base, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                                stdin=subprocess.DEVNULL)
        time.sleep(delay)
        proc.kill()
        proc.wait()
        after = {p.relative_to(out): p.read_bytes() for p in (out / "report").rglob("*")
                 if p.is_file()}
        json_file = Path("report") / "report.json"
        if after.get(json_file) == before[json_file]:
            assert after == before, delay  # killed before its swap: the old one, whole
            killed += 1
        else:  # it swapped its report in before the signal: a whole new one
            assert set(after) == set(before), delay
            before = after
    assert killed >= 2  # the seeded moments do fall inside runs
    subprocess.run(base, check=True, capture_output=True, timeout=300)  # cleans up
    assert [p.name for p in out.iterdir() if ".new-" in p.name] == []
