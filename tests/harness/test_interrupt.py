"""Ctrl-C (SIGINT, to the whole process group as a terminal sends it) and SIGTERM (to the
command alone, as `kill` and service managers send it) at any moment end a command with one
line on stderr and status 130 or 143: no output file of the render, no half-built output
folder (the previous one as it was), no process left behind (pool workers, candidate programs
and what they started). The moments are seeded and random across cold runs (an empty HOME:
no Dr.Jit kernel cache, no raycheck cache), where most of the time goes to importing,
tracing and compiling kernels, the places an interrupt used to come out as a traceback."""
from __future__ import annotations

import json
import os
import random
import re
import shlex
import shutil
import signal
import subprocess
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import pytest
from new_user import cold_env
from test_check import processes_naming

from raycheck.harness.cli import main as raycheck_main

REPO = Path(__file__).resolve().parents[2]
FALLOFF = REPO / "scenes" / "features" / "falloff.txt"
ARCH = REPO / "scenes" / "course" / "arch.txt"
SHADOWS = REPO / "scenes" / "features" / "shadows.txt"
WRAPPERS = Path(__file__).resolve().parents[1] / "wrappers"
GRACE_S = 3.0  # a launch is ~0.5-1 s on an idle core; room for a loaded CI machine
STOP_S = 15.0  # from the signal to the command's exit: a pool's workers unwinding (at most
# executor.STOP_GRACE_S, 5 s), on a loaded 2-core machine


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


@pytest.mark.usefixtures("python_sigint_handler")  # conftest.py
def test_ctrl_c_once_the_checks_folder_is_in_place_ends_it_as_finished(tmp_path, capsys,
                                                                      monkeypatch):
    """Ctrl-C at the last moment of the swap (the new folder renamed into place, its signals
    still held back) and at every Python call after it (printing the summary, returning the
    status): the check ends with its own status and summary, as a finished run, since status
    130 would say that the previous folder stands."""
    from raycheck.harness.storage import staging
    from raycheck.tracer.process import raise_interrupt

    out = tmp_path / "check"
    argv = check_argv(out) + ["--size", "4", "4", "--features", "plain"]
    assert raycheck_main(argv + ["--quiet"]) == 0
    (out / "previous").write_text("previous")
    real_finish = staging.finish_run

    def finish_then_interrupted() -> None:
        os.kill(os.getpid(), signal.SIGINT)  # arrives within the swap's signals_deferred
        real_finish()
        sys.setprofile(interrupting)

    def interrupting(frame, event, arg) -> None:
        # while the command's handler is in: after it, the signal would end this test
        if event in ("call", "c_return") and signal.getsignal(signal.SIGINT) is raise_interrupt:
            os.kill(os.getpid(), signal.SIGINT)

    monkeypatch.setattr(staging, "finish_run", finish_then_interrupted)
    capsys.readouterr()
    try:
        status = raycheck_main(argv)
    finally:
        sys.setprofile(None)
    captured = capsys.readouterr()
    assert status == 0 and "interrupted" not in captured.err, captured.err
    assert "report:" in captured.out  # the summary was printed whole
    assert not (out / "previous").exists() and (out / "check.json").is_file()


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


# --- signals at seeded random moments of cold runs -------------------------------------------

RAYCHECK = Path(sys.executable).with_name("raycheck")  # the console script a user runs


def raycheck_argv(*args: str) -> list[str]:
    base = [str(RAYCHECK)] if RAYCHECK.is_file() else [sys.executable, "-m", "raycheck.harness"]
    return base + list(args)


def start_up_seconds() -> float:
    """How long the interpreter takes to start and import the command's entry module here and
    now: a signal before that meets Python's own default handling (a traceback of its start-up,
    or death by the signal), not raycheck's."""
    times = []
    for _ in range(3):
        start = time.perf_counter()
        subprocess.run([sys.executable, "-c", "import raycheck.harness.cli"], check=True)
        times.append(time.perf_counter() - start)
    return max(times)


def handles_sigterm(pid: int) -> bool:
    """Whether process `pid` catches or ignores SIGTERM, which Python leaves at its default:
    raycheck's handlers are in (process.interrupts_raised), its start-up is over. A process
    that has gone counts as over too."""
    try:
        status = Path(f"/proc/{pid}/status").read_text()
    except OSError:
        return True
    masks = dict(line.split(":\t") for line in status.splitlines() if line.startswith("Sig"))
    bit = 1 << (signal.SIGTERM - 1)
    return bool((int(masks["SigCgt"], 16) | int(masks["SigIgn"], 16)) & bit)


def session_processes(sid: int) -> list[str]:
    """Live processes of session `sid`: 'pid name'."""
    found = []
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            stat = (entry / "stat").read_text()
        except OSError:
            continue
        name, fields = stat[stat.index("(") + 1:stat.rindex(")")], stat[stat.rindex(")") + 2:]
        state, session = fields.split()[0], int(fields.split()[4])
        if session == sid and state != "Z":
            found.append(f"{entry.name} {name}")
    return found


PROGRESS = re.compile(r"rendering: +\d+% after \d+\.\d s")


@dataclass(frozen=True)
class Interrupted:
    moment: float  # seconds after the start
    signal: int
    status: int
    stderr: str
    seconds: float  # from the signal to the exit
    left: list[str]  # processes of its session still alive once it had ended
    run_s: float  # from the start to the exit

    @property
    def finished(self) -> bool:
        """The run ended before the signal came."""
        return self.status == 0

    def problem(self) -> str | None:
        """What is wrong with how it ended, if anything."""
        if self.left:
            return f"left processes behind: {self.left}"
        if self.finished:  # (a slow render's progress line is on stderr)
            return None if "Traceback" not in self.stderr else f"finished with {self.stderr!r}"
        word = "terminated" if self.signal == signal.SIGTERM else "interrupted"
        # a render past its first second has printed its progress (tracer.cli.Progress)
        lines = [line for line in self.stderr.splitlines() if not PROGRESS.fullmatch(line)]
        if self.status != 128 + self.signal or len(lines) != 1 or \
                not lines[0].endswith(f": {word}"):
            return f"status {self.status}, stderr {self.stderr!r}"
        if self.seconds > STOP_S:
            return f"took {self.seconds:.1f} s to stop"
        return None


def interrupt_at(argv: list[str], env: dict[str, str], moment: float,
                 signum: int) -> Interrupted:
    """Runs argv in a session of its own and sends `signum` `moment` seconds after its start:
    SIGINT to its process group (a terminal's Ctrl-C), SIGTERM to the process alone."""
    proc = subprocess.Popen(argv, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                            stdin=subprocess.DEVNULL, text=True, start_new_session=True)
    began = time.perf_counter()
    try:
        proc.wait(timeout=moment)  # it ended before its moment: no signal
    except subprocess.TimeoutExpired:
        # a loaded machine can start the interpreter slower than start_up_seconds measured
        while not handles_sigterm(proc.pid) and proc.poll() is None:
            time.sleep(0.002)
        if signum == signal.SIGINT:
            os.killpg(proc.pid, signum)
        else:
            proc.send_signal(signum)
    sent = time.perf_counter()
    _, err = proc.communicate(timeout=120)
    ended = time.perf_counter()
    # the multiprocessing resource tracker ends once the command and its workers have closed
    # its pipe: a moment's grace for it
    deadline = time.monotonic() + 2.0
    while (left := session_processes(proc.pid)) and time.monotonic() < deadline:
        time.sleep(0.05)
    for entry in left:
        os.kill(int(entry.split()[0]), signal.SIGKILL)
    return Interrupted(moment, signum, proc.returncode, err, ended - sent, left, ended - began)


def interrupted_runs(seed: int, count: int, start: float, span: float,
                     run_one: Callable[[int, float, int], Interrupted]) -> list[Interrupted]:
    """`run_one(k, moment, signal)` at seeded random moments in [start, span) until `count`
    runs were interrupted before they ended, SIGINT and SIGTERM in turn; at most 3 * count
    runs. A run that ended before its moment (how long a run takes changes with the machine's
    load) shortens the span to its own length for the moments after it."""
    rng = random.Random(seed)
    runs: list[Interrupted] = []
    while (hit := sum(not r.finished for r in runs)) < count and len(runs) < 3 * count:
        moment = start + rng.random() * max(0.0, span - start)
        runs.append(run_one(len(runs), moment, (signal.SIGINT, signal.SIGTERM)[hit % 2]))
        if runs[-1].finished:
            span = min(span, runs[-1].run_s)
    return runs


def tree(folder: Path) -> dict[str, bytes]:
    return {str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*"))
            if p.is_file()}


def assert_interrupts_end_cleanly(runs: list[Interrupted], outcome, count: int) -> None:
    """Every run ended cleanly (Interrupted.problem, and `outcome(k)` on its files), and
    `count` of them were interrupted before they ended (interrupted_runs)."""
    problems = [f"{r.moment:.2f} s, {signal.Signals(r.signal).name}: {p}" for k, r in
                enumerate(runs) if (p := r.problem() or outcome(k, r))]
    assert not problems, "\n".join(problems)
    assert sum(not r.finished for r in runs) >= count, runs


def test_signals_at_random_moments_of_a_cold_check(tmp_path, full_run):
    """A check in a pool of two workers (spawned processes, each tracing and compiling its
    kernels), with a jittered case (64 realisations): whatever it was doing, the previous
    output folder stays as it was, byte for byte, unless the run had finished."""
    argv = raycheck_argv("check", "--renderer", "tracer", str(FALLOFF), "--size", "16", "16",
                         "--features", "plain,shadows,jitter", "--realisations", "16", "-j",
                         "2", "--quiet")
    first = tmp_path / "first"
    start = time.perf_counter()
    subprocess.run(argv + ["--out", str(first / "out")], env=cold_env(first / "home"),
                   check=True, capture_output=True, timeout=300)
    span = time.perf_counter() - start
    previous = tree(first / "out")
    folders = []

    def run_one(k: int, moment: float, signum: int) -> Interrupted:
        run = tmp_path / f"run{k}"
        shutil.copytree(first / "out", run / "out")
        folders.append(run)
        return interrupt_at(argv + ["--out", str(run / "out")], cold_env(run / "home"),
                            moment, signum)

    count = 36 if full_run else 12
    runs = interrupted_runs(28, count, start_up_seconds(), span, run_one)

    def outcome(k: int, r: Interrupted) -> str | None:
        out, run = folders[k] / "out", folders[k]
        if [p.name for p in run.iterdir() if ".new-" in p.name or ".old-" in p.name]:
            return "a staging folder was left"
        if r.finished:
            return None if set(tree(out)) == set(previous) else "a different folder"
        return None if tree(out) == previous else "the previous folder changed"

    assert_interrupts_end_cleanly(runs, outcome, count)


@pytest.mark.parametrize("command", ["render", pytest.param("reference", marks=pytest.mark.full)])
def test_signals_at_random_moments_of_a_cold_render(command, tmp_path, full_run):
    """`raycheck render` (and Mitsuba's `reference`) of three images: whatever it was doing,
    the three files are the old ones or the new ones, all of them, and nothing else is in
    their folder."""
    names = ("a.png", "n.png", "d.png")

    def argv(folder: Path) -> list[str]:
        return raycheck_argv(command, "-input", str(ARCH), "-size", "48", "48", "-shadows",
                             "-bounces", "3", "-jitter", "-output", str(folder / names[0]),
                             "-normals", str(folder / names[1]), "-depth", "6", "16",
                             str(folder / names[2]))

    first = tmp_path / "first"
    (first / "images").mkdir(parents=True)
    start = time.perf_counter()
    subprocess.run(argv(first / "images"), env=cold_env(first / "home"), check=True,
                   capture_output=True, timeout=300)
    span = time.perf_counter() - start
    rendered = tree(first / "images")
    old = {name: b"old " + name.encode() for name in names}
    folders = []

    def run_one(k: int, moment: float, signum: int) -> Interrupted:
        folder = tmp_path / f"run{k}"
        (folder / "images").mkdir(parents=True)
        for name, data in old.items():
            (folder / "images" / name).write_bytes(data)
        folders.append(folder)
        return interrupt_at(argv(folder / "images"), cold_env(folder / "home"), moment, signum)

    count = 24 if full_run else 12
    runs = interrupted_runs(130, count, start_up_seconds(), span, run_one)

    def outcome(k: int, r: Interrupted) -> str | None:
        files = tree(folders[k] / "images")
        return None if files == (rendered if r.finished else old) else \
            f"files {sorted(files)}, new ones: {[n for n in files if files[n] != old.get(n)]}"

    assert_interrupts_end_cleanly(runs, outcome, count)


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM])
def test_an_interrupt_stops_every_candidate_and_what_it_started(signum, tmp_path):
    """Two cases in two workers, each running a candidate that starts a child and sleeps (in
    sessions of their own, where a terminal's Ctrl-C does not reach): the check stops its
    workers, they kill their candidates' process groups, and nothing of them is left. The
    program's first case runs alone (matrix.first_waves) until its timeout; then the first
    cases of the two other scenes run together."""
    pidfile = tmp_path / f"pids-{os.getpid()}-{time.time_ns()}.txt"  # also the argv marker
    renderer = shlex.join([sys.executable, str(WRAPPERS / "orphan.py"), str(pidfile)])
    argv = raycheck_argv("check", "--renderer", renderer, str(FALLOFF), str(ARCH),
                         str(SHADOWS), "--size", "8", "8", "--features", "plain", "--timeout",
                         "2", "-j", "2", "--out", str(tmp_path / "out"))
    env = dict(os.environ, PYTHONUNBUFFERED="1")
    proc = subprocess.Popen(argv, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                            stdin=subprocess.DEVNULL, text=True, start_new_session=True)
    deadline = time.monotonic() + 120
    while len(processes_naming(str(pidfile))) < 4:  # both candidates and their children
        assert proc.poll() is None and time.monotonic() < deadline
        time.sleep(0.05)
    if signum == signal.SIGINT:
        os.killpg(proc.pid, signum)
    else:
        proc.send_signal(signum)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 128 + signum and err.count("\n") == 1, err
    assert processes_naming(str(pidfile)) == []
    assert not (tmp_path / "out").exists()


@pytest.mark.full  # the cluster's start and its workers' imports: about 10 s
def test_signals_at_random_moments_of_a_check_on_a_dask_cluster(tmp_path):
    """The cases run on a Dask cluster's workers (processes of this test, not the command's):
    the command ends with its one line whatever it was waiting for, connecting included."""
    from distributed import LocalCluster

    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                      dashboard_address=None, protocol="tcp") as cluster:
        argv = raycheck_argv("check", "--renderer", "tracer", str(FALLOFF), "--size", "16",
                             "16", "--features", "plain,shadows,jitter", "--realisations",
                             "16", "--scheduler", cluster.scheduler_address, "--quiet")
        for first in ("cold", "warm"):  # the workers keep their kernels and the cache
            start = time.perf_counter()
            subprocess.run(argv + ["--out", str(tmp_path / first)], check=True,
                           capture_output=True, timeout=300)
        span = time.perf_counter() - start
        runs = interrupted_runs(
            8786, 8, start_up_seconds(), span,
            lambda k, moment, signum: interrupt_at(
                argv + ["--out", str(tmp_path / f"run{k}")], dict(os.environ), moment, signum))

    def outcome(k: int, r: Interrupted) -> str | None:
        made = (tmp_path / f"run{k}").exists()
        return None if made == r.finished else "an output folder of an interrupted run"

    assert_interrupts_end_cleanly(runs, outcome, 8)


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM])
def test_an_interrupt_while_connecting_to_a_silent_scheduler_ends_in_one_line(signum, tmp_path):
    """A scheduler address that accepts the connection and never answers: the command waits
    in Dask's Client constructor (its timeout is 10 s) when the signal comes; the half-made
    client is closed then, not by the garbage collector after the event loop has gone (which
    printed a traceback after the one line)."""
    import socket

    with socket.socket() as silent:
        silent.bind(("127.0.0.1", 0))
        silent.listen(8)
        argv = raycheck_argv("check", "--renderer", "tracer", str(FALLOFF), "--size", "8", "8",
                             "--features", "plain", "--scheduler",
                             f"tcp://127.0.0.1:{silent.getsockname()[1]}", "--quiet",
                             "--out", str(tmp_path / "out"))
        run = interrupt_at(argv, dict(os.environ), start_up_seconds() + 2.0, signum)
    assert not run.finished and run.problem() is None, run
    assert not (tmp_path / "out").exists()
