"""The sandbox around a candidate program (harness/renderers/sandbox.py), tried by a hostile
one (tests/hostile/hostile.c, built here with the system's C compiler): each attempt is
stopped and comes back as the candidate's error. Each attempt also runs without the sandbox,
where it gets through: the test of the sandbox is not one that cannot fail."""
from __future__ import annotations

import os
import shutil
import signal
import subprocess
import time
from pathlib import Path

import pytest
from listener import listening
from test_check import processes_naming

from raycheck.harness.renderers import CommandRenderer, Limits, RenderError
from raycheck.harness.renderers.sandbox import (
    PROCESS_LIMIT,
    SandboxError,
    SandboxMode,
    sandbox_for,
)

HOSTILE = Path(__file__).resolve().parents[1] / "hostile" / "hostile.c"
# where bubblewrap is installed (the project's install step installs it) it must work
needs_sandbox = pytest.mark.skipif(shutil.which("bwrap") is None,
                                   reason="bubblewrap is not installed")


@pytest.fixture(scope="module")
def hostile(tmp_path_factory) -> Path:
    program = tmp_path_factory.mktemp("hostile") / "hostile"
    program.parent.chmod(0o755)  # a root grader's sandbox runs it as another user
    subprocess.run(["cc", "-O1", "-o", str(program), str(HOSTILE)], check=True)
    return program


def stopped(error: RenderError | None) -> bool:
    """The program ran in the sandbox and its attempt failed there (not: bwrap could not
    start it)."""
    return error is not None and error.code == "exit_status" and "stopped: " in error.log


def attempt(program: Path, what: str, arg: str, folder: Path, sandboxed: bool,
            limits: Limits = Limits(timeout_s=60)) -> RenderError | None:
    """Runs `hostile what arg` in `folder` (its case folder); the error it ended with."""
    folder.mkdir(parents=True, exist_ok=True)
    sandbox = sandbox_for(SandboxMode.REQUIRED) if sandboxed else None
    renderer = CommandRenderer([str(program), what, arg], limits, sandbox=sandbox)
    try:
        renderer.run(renderer.argv, folder, folder)
    except RenderError as e:
        return e
    return None


@needs_sandbox
@pytest.mark.parametrize("sandboxed", [True, False])
def test_writing_outside_its_folder(hostile, tmp_path, sandboxed):
    outside = tmp_path / "escape.txt"
    error = attempt(hostile, "write_outside", str(outside), tmp_path / "case", sandboxed)
    if sandboxed:
        assert not outside.exists()
        assert stopped(error), (error, error and error.log)
    else:
        assert outside.read_text() == "escaped\n" and error is None


@needs_sandbox
@pytest.mark.parametrize("secret", ["other-submission/src/main.cpp", "home/.ssh/id_rsa"])
@pytest.mark.parametrize("sandboxed", [True, False])
def test_reading_the_graders_files(hostile, tmp_path, secret, sandboxed):
    path = tmp_path / secret
    path.parent.mkdir(parents=True)
    path.write_text("the grader's secret\n")
    case = tmp_path / "case"
    error = attempt(hostile, "read_secret", f"@{path}", case, sandboxed)
    if sandboxed:
        assert not (case / "stolen.txt").exists()
        assert stopped(error), (error, error and error.log)
    else:
        assert (case / "stolen.txt").read_text() == "the grader's secret\n"


@needs_sandbox
@pytest.mark.parametrize("sandboxed", [True, False])
def test_opening_a_network_socket(hostile, tmp_path, sandboxed):
    with listening() as (port, heard):
        error = attempt(hostile, "network", str(port), tmp_path / "case", sandboxed)
    if sandboxed:
        assert heard == [] and stopped(error), (error, error and error.log)
    else:
        assert heard == [b"hello from the sandbox\n"]


@needs_sandbox
@pytest.mark.parametrize("sandboxed", [True, False])
def test_a_fork_bomb(hostile, tmp_path, sandboxed):
    """Without the sandbox (as root, RLIMIT_NPROC binds nobody) all the children start; in it
    the process limit stops the bomb, and none of its children outlives the run."""
    wanted = PROCESS_LIMIT + 200
    case = tmp_path / "case"
    error = attempt(hostile, "fork_bomb", str(wanted), case, sandboxed)
    started = int((case / "stdout.txt").read_text().split()[1])
    if sandboxed:
        assert started < PROCESS_LIMIT, started
        assert stopped(error), (error, error and error.log)
    elif os.geteuid() == 0:
        assert started == wanted and error is None
    assert gone(str(hostile))


def gone(marker: str, grace_s: float = 5.0) -> bool:
    """No process with `marker` in its argv is left, after a grace for those the kernel is
    still killing (a PID namespace's processes die as it ends, one by one)."""
    deadline = time.monotonic() + grace_s
    while processes_naming(marker) and time.monotonic() < deadline:
        time.sleep(0.05)
    return processes_naming(marker) == []


@needs_sandbox
@pytest.mark.parametrize("sandboxed", [True, False])
def test_leaving_a_daemon_behind(hostile, tmp_path, sandboxed):
    """A grandchild in a session of its own escapes the kill of the program's process group;
    the sandbox's PID namespace ends with the program."""
    marker = f"raycheck-daemon-{os.getpid()}-{time.time_ns()}"
    attempt(hostile, "daemon", marker, tmp_path / "case", sandboxed)
    if sandboxed:
        assert gone(marker)
        return
    left = processes_naming(marker)
    for pid in left:
        os.kill(pid, signal.SIGKILL)
    assert left


@needs_sandbox
def test_filling_the_disk(hostile, tmp_path):
    """The folder is watched: past its size limit the program is killed, and what it wrote is
    at most a poll's worth past the limit."""
    limits = Limits(timeout_s=60, disk_bytes=16 << 20)
    case = tmp_path / "case"
    error = attempt(hostile, "fill_disk", "400", case, True, limits)
    assert error is not None and error.code == "disk_limit", error
    written = sum(p.stat().st_size for p in case.glob("fill-*.bin"))
    assert limits.disk_bytes < written < 400 << 20


def test_required_where_bubblewrap_cannot_run_is_an_error(monkeypatch):
    import raycheck.harness.renderers.sandbox as sandbox

    monkeypatch.setenv("PATH", "/nonexistent")
    monkeypatch.setattr(sandbox, "_probed", {})
    sandbox._working.cache_clear()
    try:
        with pytest.raises(SandboxError, match="not installed"):
            sandbox_for(SandboxMode.REQUIRED)
        assert sandbox_for(SandboxMode.AUTO) is None
    finally:
        sandbox._working.cache_clear()
