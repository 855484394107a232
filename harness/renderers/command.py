"""Any program that takes the course's command line, run as an untrusted subprocess.

Each render runs in a fresh temporary folder holding a comment-free copy of the scene and of
every mesh and cube-map face it reads (at the same relative places, so the scene's relative
paths work), with the scene's folder as the working directory and the output files named
there. The program gets no stdin, a minimal environment, its own process group (killed whole
after it exits or times out: no orphans), and resource limits (CPU time, address space, file
size). Everything that can go wrong is a RenderError or KindError with a finding code:

    timeout         ran past the wall-clock limit (killed)
    crash           ended by a signal (SIGSEGV, SIGABRT, SIGKILL from a limit...)
    exit_status     exited with a non-zero status
    missing_output  exited 0 without writing an image it was asked for (with none at all:
                    what a course program does when it cannot parse the scene)
    bad_png         an output that is not a readable PNG (truncated, garbage, empty)
    wrong_size      a PNG of another size than -size asked for
"""
from __future__ import annotations

import contextlib
import hashlib
import os
import resource
import shlex
import shutil
import signal
import subprocess
import tempfile
import threading
import time
from dataclasses import dataclass, field
from functools import partial
from pathlib import Path
from typing import Iterator

import numpy as np

from raycheck.tracer.process import signals_deferred
from raycheck.tracer.scene import SceneError, load_scene
from raycheck.tracer.scene.assets import asset_files, without_comments
from raycheck.tracer.scene.request import RenderRequest

from ..check_options import DEFAULT_TIMEOUT_S
from .base import TOOLS, Capabilities, Debugger, Images, KindError, RenderError
from .sandbox import Sandbox, limit_processes

DEFAULT_MEMORY_BYTES = 4 << 30
DEFAULT_FILE_BYTES = 1 << 30
DEFAULT_DISK_BYTES = 2 << 30
DISK_POLL_S = 0.05
LOG_TAIL_LINES = 20
LOG_TAIL_BYTES = 4096
OUTPUT_NAMES = {"color": "out.png", "normals": "normals.png", "depth": "depth.png"}
# what the program's environment keeps from ours: enough to find interpreters and libraries
# (HOME too: a renderer's own caches, such as Dr.Jit's kernel cache, live there). The limits
# bound a buggy program; hostile code needs the sandbox (sandbox.py), which sets its own.
PASSED_ENV = ("PATH", "HOME", "LANG", "LC_ALL", "LD_LIBRARY_PATH", "PYTHONPATH", "VIRTUAL_ENV",
              "DRJIT_LIBLLVM_PATH", "DRJIT_CACHE_DIR")

MEMCHECK_REDZONE = 4096  # bytes about each heap block (valgrind's largest)

# gdb's commands once the program stopped (on a signal: else the first fails and gdb stops
# there), their output alone in the log: the signal, the faulting address and the stack
# pointer (a fault at the stack pointer is a stack overflow), the innermost frames, and the
# outermost (whose numbers give the stack's depth)
GDB_SCRIPT = """set width 0
set print frame-arguments none
set logging file {log}
set logging overwrite on
set logging redirect on
set logging enabled on
p $_siginfo.si_signo
p $_siginfo._sifields._sigfault.si_addr
p $sp
bt 40
bt -3
"""
# Where a program that runs on is: stopped after HANG_WAIT_S, its stack is printed, and each
# frame, innermost first, is let run until it returns, for HANG_STEP_S at most: the first that
# does not is printed (STUCK). A process of its own sends each interrupt (a timer's thread
# would wait on Python's lock while gdb runs the program).
HANG_WAIT_S = 2.0
HANG_STEP_S = 1.0
HANG_SCRIPT = """set width 0
set pagination off
set confirm off
set print frame-arguments none
set logging file {log}
set logging overwrite on
set logging redirect on
set logging enabled on
python
import subprocess
def alarm(seconds):
    pid = gdb.selected_inferior().pid
    return subprocess.Popen(["sh", "-c", f"sleep {{seconds}} && kill -INT {{pid}}"])
end
starti
python first = alarm({wait})
continue
python first.wait()
bt 40
python
while True:
    name = gdb.newest_frame().name() or "??"
    timer = alarm({step})
    gdb.execute("finish", to_string=True)
    if timer.poll() is not None:
        gdb.write(f"STUCK {{name}}\\n")
        break
    timer.kill()
    timer.wait()
end
kill
"""


@dataclass(frozen=True)
class Limits:
    timeout_s: float = DEFAULT_TIMEOUT_S    # wall clock per render
    memory_bytes: int = DEFAULT_MEMORY_BYTES  # address space (RLIMIT_AS)
    file_bytes: int = DEFAULT_FILE_BYTES    # largest file it may write (RLIMIT_FSIZE)
    disk_bytes: int = DEFAULT_DISK_BYTES    # all it writes into its folder (watched)

    @property
    def cpu_s(self) -> int:
        # CPU time over all threads: generous for a multithreaded renderer, still a bound
        return int(self.timeout_s * max(1, os.cpu_count() or 1)) + 1


def split_command(command: str | list[str]) -> list[str]:
    """A command string split as a POSIX shell would (quotes, escapes), or a list as given."""
    argv = shlex.split(command) if isinstance(command, str) else list(command)
    if not argv:
        raise ValueError("the renderer command is empty")
    return argv


def program_file(argv: list[str]) -> Path | None:
    """The file that identifies the program: the last argument naming an existing file (the
    script of `python3 my_tracer.py`), else the executable found on PATH."""
    for arg in reversed(argv[1:]):
        if not arg.startswith("-") and Path(arg).is_file():
            return Path(arg)
    found = shutil.which(argv[0])
    return Path(found) if found else None


def sha256_file(path: Path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for chunk in iter(lambda: f.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


def _tail(path: Path) -> str:
    try:
        with open(path, "rb") as f:
            f.seek(0, os.SEEK_END)
            f.seek(max(0, f.tell() - LOG_TAIL_BYTES))
            data = f.read()
    except OSError:
        return ""
    lines = data.decode("utf-8", "replace").splitlines()[-LOG_TAIL_LINES:]
    return "\n".join(lines)


def stage_scene(scene_path: Path, folder: Path) -> Path:
    """Copy the scene (without comments) and its assets under folder, keeping their places
    relative to each other; returns the copy's path. (A scene naming an asset by an absolute
    path still reads the original there.)"""
    scene_path = Path(scene_path)
    scene = load_scene(scene_path)
    here = scene_path.resolve().parent
    assets = [Path(p).resolve() for p in asset_files(scene)]
    root = Path(os.path.commonpath([here] + [p.parent for p in assets]))
    copy = folder / here.relative_to(root) / scene_path.name
    copy.parent.mkdir(parents=True, exist_ok=True)
    copy.write_text(without_comments(scene_path.read_text(encoding="utf-8")), encoding="utf-8")
    for asset in assets:
        target = folder / asset.relative_to(root)
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(asset, target)
    return copy


def read_png(path: Path, size: tuple[int, int]) -> np.ndarray | KindError:
    """The PNG's pixels as (h, w, 3) uint8, or why they cannot be used."""
    from PIL import Image, UnidentifiedImageError

    if not path.is_file():
        return KindError("missing_output", f"{path.name} was not written")
    try:
        with Image.open(path) as im:
            if im.format != "PNG":
                return KindError("bad_png", f"{path.name} is not a PNG (it is {im.format})")
            if im.size != size:  # from the header, before decoding anything
                return KindError("wrong_size", f"{path.name} is {im.size[0]}x{im.size[1]}, "
                                               f"-size asked for {size[0]}x{size[1]}")
            return np.asarray(im.convert("RGB"))
    except (UnidentifiedImageError, OSError, ValueError, SyntaxError) as e:
        return KindError("bad_png", f"{path.name} is not a readable PNG ({e})")


@contextlib.contextmanager
def staged(scene: Path) -> Iterator[tuple[Path, Path]]:
    """A fresh temporary folder, and the scene's copy staged below it (stage_scene)."""
    with tempfile.TemporaryDirectory(prefix="raycheck-case-") as tmp:
        folder = Path(tmp)
        try:
            copy = stage_scene(scene, folder / "scene")
        except (SceneError, OSError) as e:
            raise RenderError("bad_input", f"cannot stage the scene: {e}") from None
        yield folder, copy


def is_native(path: Path) -> bool:
    """Whether the file is an ELF executable (a compiled program, not a script)."""
    try:
        with open(path, "rb") as f:
            return f.read(4) == b"\x7fELF"
    except OSError:
        return False


class CommandSession:
    def __init__(self, renderer: CommandRenderer, scene: Path, request: RenderRequest) -> None:
        self.renderer = renderer
        self.scene = Path(scene)
        self.request = request

    def render(self) -> Images:
        with staged(self.scene) as (folder, copy):
            argv = self.renderer.argv + self.request.to_argv(copy.name, OUTPUT_NAMES)
            try:
                seconds, log = self.renderer.run(argv, copy.parent, folder)
            except RenderError as e:
                e.written = tuple(k for k in self.request.kinds
                                  if (copy.parent / OUTPUT_NAMES[k]).is_file())
                raise
            images, errors = {}, {}
            for kind in self.request.kinds:
                got = read_png(copy.parent / OUTPUT_NAMES[kind], self.request.size)
                if isinstance(got, KindError):
                    errors[kind] = got
                else:
                    images[kind] = got
            if not images and all(e.code == "missing_output" for e in errors.values()):
                raise RenderError("missing_output", "exited with status 0 but wrote none of its "
                                  "images (a course program does this when it cannot parse "
                                  "the scene)", log)
            return Images(images, seconds, errors, log)

    def close(self) -> None:
        pass


@dataclass
class CommandRenderer:
    """A course renderer run as `argv + course flags`."""

    argv: list[str]
    limits: Limits = field(default_factory=Limits)
    name: str = ""
    sandbox: Sandbox | None = None  # None: rlimits only
    caps: Capabilities = Capabilities(float_images=False, seedable=False, warm_reruns=False)

    def __post_init__(self) -> None:
        # the program runs in the case's folder: paths relative to ours must still name it
        self.argv = [os.path.abspath(a) if (i == 0 and "/" in a) or
                     (i > 0 and not a.startswith("-") and Path(a).is_file()) else a
                     for i, a in enumerate(self.argv)]
        if not self.name:
            self.name = " ".join(Path(a).name if i == 0 else a for i, a in enumerate(self.argv))

    @classmethod
    def from_string(cls, command: str, limits: Limits | None = None) -> CommandRenderer:
        return cls(split_command(command), limits or Limits())

    def identity(self) -> dict:
        program = program_file(self.argv)
        return {"command": list(self.argv),
                "sha256": sha256_file(program) if program else None,
                "file": str(program) if program else None,
                "sandbox": "bubblewrap" if self.sandbox is not None else "none"}

    def open(self, scene: Path, request: RenderRequest) -> CommandSession:
        return CommandSession(self, scene, request)

    def debug(self, scene: Path, request: RenderRequest, debugger: Debugger) -> str | None:
        """What a debugger says of the program on the request: it runs once more under gdb
        (which prints the signal, the fault and the stack pointer, and the innermost and
        outermost frames where it stopped: GDB_SCRIPT) or valgrind's memcheck (its XML: each
        invalid read and write where it was made, and the fatal signal), in the sandbox if
        any, within the same limits. None where the debugger is not installed, the command's
        program is not a native executable (a script, an interpreter's), the program did not
        stop on a signal under gdb, or the run ran out of time."""
        tool = shutil.which(TOOLS[debugger])
        program = shutil.which(self.argv[0])
        if tool is None or program is None or not is_native(Path(program)) \
                or program_file(self.argv) != Path(program):
            return None
        with staged(scene) as (folder, copy):
            log = folder / "debugger.txt"
            if debugger == Debugger.GDB:
                script = folder / "crash.gdb"
                script.write_text(GDB_SCRIPT.format(log=log))
                prefix = [tool, "-batch", "-nx", "-ex", "run", "-x", str(script), "--args"]
            elif debugger == Debugger.HANG:
                script = folder / "hang.gdb"
                script.write_text(HANG_SCRIPT.format(log=log, wait=HANG_WAIT_S,
                                                     step=HANG_STEP_S))
                prefix = [tool, "-batch", "-nx", "-x", str(script), "--args"]
            else:
                # every invalid access, not only the first: a write far before an array
                # (row -1) reads as a wild one, the next ones as just outside it. The widest
                # redzone about each block: a row -1 of a wide image lands in its array's,
                # not in the block before (where it reads as valid). Uninitialised values are
                # no invalid access: not tracked.
                prefix = [tool, "-q", "--xml=yes", f"--xml-file={log}", "--leak-check=no",
                          "--num-callers=40", "--undef-value-errors=no",
                          f"--redzone-size={MEMCHECK_REDZONE}"]
            try:
                self.run([*prefix, *self.argv, *request.to_argv(copy.name, OUTPUT_NAMES)],
                         copy.parent, folder)
            except RenderError as e:
                # gdb stops its script where the program did not crash (or ran on); under
                # valgrind the program may crash or exit as it does alone
                if debugger != Debugger.MEMCHECK or e.code not in ("crash", "exit_status"):
                    return None
            try:
                return log.read_text(encoding="utf-8", errors="replace")
            except OSError:
                return None

    def _limit_resources(self, processes: int | None) -> None:  # in the child, before exec
        lim = self.limits
        resource.setrlimit(resource.RLIMIT_CPU, (lim.cpu_s, lim.cpu_s))
        resource.setrlimit(resource.RLIMIT_AS, (lim.memory_bytes, lim.memory_bytes))
        resource.setrlimit(resource.RLIMIT_FSIZE, (lim.file_bytes, lim.file_bytes))
        resource.setrlimit(resource.RLIMIT_CORE, (0, 0))
        if processes is not None:
            limit_processes(processes)

    def run(self, argv: list[str], cwd: Path, home: Path) -> tuple[float, str]:
        # home: the case's own folder, for the program's temporary files and our logs
        """Runs argv in cwd (in the sandbox, if any, with home its only writable folder);
        returns (seconds, the last lines of its stdout and stderr), or raises RenderError for
        a timeout, a crash, a non-zero exit, a folder over its size limit or a program that
        cannot be started."""
        out_path, err_path = home / "stdout.txt", home / "stderr.txt"
        processes = self.sandbox.process_limit() if self.sandbox is not None else None
        start = time.perf_counter()
        with open(out_path, "wb") as out, open(err_path, "wb") as err, \
                self._command(argv, cwd, home) as (command, env):
            watch = Watch(self.limits, home)
            try:
                # an interrupt while the program starts is raised once the watch holds it,
                # so that the `finally` below kills its process group
                with signals_deferred():
                    try:
                        watch.start(subprocess.Popen(
                            command, cwd=cwd, stdin=subprocess.DEVNULL, stdout=out,
                            stderr=err, env=env, start_new_session=True,
                            preexec_fn=partial(self._limit_resources, processes)))
                    except OSError as e:
                        raise RenderError("exit_status", f"cannot run {argv[0]}: "
                                          f"{e.strerror or e}") from None
                code = watch.wait()
            finally:
                watch.stop()  # the program and anything it left running
        seconds = time.perf_counter() - start
        log = "\n".join(t for t in (_tail(out_path), _tail(err_path)) if t)
        if watch.ended == "timeout":
            raise RenderError("timeout", f"no result after {self.limits.timeout_s:g} s "
                              "(killed)", log)
        if watch.ended == "disk_limit":
            raise RenderError("disk_limit", "wrote more than "
                              f"{self.limits.disk_bytes / (1 << 20):g} MiB into its folder "
                              "(killed)", log)
        if self.sandbox is not None and code > 128 and _is_signal(code - 128):
            code = 128 - code  # bwrap passes a signal's death on as 128 + the signal
        if code < 0:
            raise RenderError("crash", f"killed by signal {_signal_name(-code)}", log)
        if code != 0:
            raise RenderError("exit_status", f"exited with status {code}", log)
        return seconds, log

    @contextlib.contextmanager
    def _command(self, argv: list[str], cwd: Path, home: Path) -> Iterator[
            tuple[list[str], dict[str, str]]]:
        """The command line and environment that run argv: as it is with a minimal
        environment, or in the sandbox (which sets the environment inside)."""
        if self.sandbox is None:
            env = {k: os.environ[k] for k in PASSED_ENV if k in os.environ}
            env["TMPDIR"] = str(home)
            yield argv, env
            return
        self.sandbox.own(home)
        yield self.sandbox.command(argv, home, cwd), {}


class Watch:
    """Waits for a started program, and kills its process group when it runs past the time
    limit or its folder grows past the size limit (`ended` then says which). One thread
    waits: Popen.wait(timeout) polls, sleeping up to 50 ms between looks, and rounded the
    times up to its steps."""

    def __init__(self, limits: Limits, folder: Path) -> None:
        self.limits = limits
        self.folder = folder
        self.ended: str | None = None
        self._proc: subprocess.Popen | None = None
        self._done = threading.Event()
        self._thread = threading.Thread(target=self._watch, daemon=True)

    def start(self, proc: subprocess.Popen) -> None:
        self._proc = proc
        self._thread.start()

    def wait(self) -> int:
        assert self._proc is not None
        return self._proc.wait()

    def stop(self) -> None:
        self._done.set()
        if self._proc is not None:
            _kill_group(self._proc.pid)
            self._proc.wait()
            self._thread.join()

    def _watch(self) -> None:
        assert self._proc is not None
        deadline = time.monotonic() + self.limits.timeout_s
        while not self._done.wait(min(DISK_POLL_S, max(0.0, deadline - time.monotonic()))):
            if self._proc.poll() is not None:
                return
            if time.monotonic() >= deadline:
                self.ended = "timeout"
            elif folder_bytes(self.folder) > self.limits.disk_bytes:
                self.ended = "disk_limit"
            else:
                continue
            _kill_group(self._proc.pid)
            return


def folder_bytes(folder: Path) -> int:
    """The disk space the files below folder take (allocated blocks: a sparse file counts
    what it holds)."""
    total = 0
    stack = [folder]
    while stack:
        try:
            with os.scandir(stack.pop()) as entries:
                for entry in entries:
                    if entry.is_dir(follow_symlinks=False):
                        stack.append(Path(entry.path))
                    total += entry.stat(follow_symlinks=False).st_blocks * 512
        except OSError:  # removed while we looked, or not ours to read
            continue
    return total


def _is_signal(number: int) -> bool:
    try:
        signal.Signals(number)
    except ValueError:
        return False
    return True


def _signal_name(number: int) -> str:
    try:
        return signal.Signals(number).name
    except ValueError:  # a real-time or unknown signal
        return str(number)


def _kill_group(pgid: int) -> None:
    try:
        os.killpg(pgid, signal.SIGKILL)
    except (ProcessLookupError, PermissionError):
        pass
