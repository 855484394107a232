"""Untrusted programs (a student's renderer, its build) in a bubblewrap sandbox.

What the program sees (bwrap's own namespaces, no daemon):
    /usr, /bin, /lib* read-only, and the few files of /etc that the loader and the compilers
    read; nothing else of the machine: not the grader's home (~/.ssh), not other
    submissions, not the repository
    its own folder (the case's, or the build's) writable, at the same path as outside
    the folders its command names (the program's own, an interpreter's) read-only, and any the
    teacher adds (--sandbox-read)
    a private /tmp (a tmpfs of TMP_BYTES), no network (only a loopback that is down), its own
    PID namespace (when it ends, everything it started ends), a minimal environment
and at most PROCESS_LIMIT processes of its own (RLIMIT_NPROC). The kernel exempts root from
that limit: a grader running as root runs bwrap as root (it mounts by path, whatever the
folders' modes) and the program as an unprivileged user (SANDBOX_UID, through setpriv),
which owns the writable folder for the run. A grader running as itself gets bwrap's own user
namespace, and the limit counts on top of the processes it already has.
"""
from __future__ import annotations

import functools
import os
import shutil
import subprocess
from dataclasses import dataclass, replace
from enum import StrEnum
from pathlib import Path

SYSTEM_PATHS = ("/usr", "/bin", "/sbin", "/lib", "/lib32", "/lib64", "/libx32")
# what the dynamic loader, the C++ toolchain (Debian's alternatives) and getpwuid read; not
# /etc as a whole (its secrets are root's, and the sandbox's user maps to the grader's)
ETC_PATHS = ("/etc/ld.so.cache", "/etc/ld.so.conf", "/etc/ld.so.conf.d", "/etc/alternatives",
             "/etc/localtime", "/etc/passwd", "/etc/group", "/etc/nsswitch.conf")
TMP_BYTES = 64 << 20
PROCESS_LIMIT = 256
SANDBOX_UID = 65534  # nobody: when the grader is root
SETPRIV = "/usr/bin/setpriv"  # util-linux: Debian has it on every system
ENV = {"PATH": "/usr/local/bin:/usr/bin:/bin", "HOME": "/tmp", "TMPDIR": "/tmp",
       "LANG": "C.UTF-8"}
PROBE_TIMEOUT_S = 20.0


class SandboxMode(StrEnum):
    OFF = "off"            # the program runs with rlimits only
    AUTO = "auto"          # the sandbox where bubblewrap runs, else rlimits and a warning
    REQUIRED = "required"  # the sandbox, or an error before any work


class SandboxError(RuntimeError):
    """--sandbox required where bubblewrap cannot run (one line, exit status 2)."""


@dataclass(frozen=True)
class Sandbox:
    bwrap: str
    uid: int | None  # run as this user (the grader is root: setpriv), else as the grader
    readable: tuple[Path, ...] = ()  # more read-only folders (--sandbox-read)

    def command(self, argv: list[str], writable: Path, cwd: Path) -> list[str]:
        """bwrap's command line running argv in cwd with `writable` its only writable
        folder."""
        if self.uid is None:  # bwrap makes a user namespace of its own
            args = [self.bwrap, "--unshare-all"]
        else:
            # a root grader's bwrap mounts by path whatever the folders' modes; the program
            # runs as `uid` in the machine's user namespace, where RLIMIT_NPROC counts it
            args = [self.bwrap, "--unshare-pid", "--unshare-net", "--unshare-ipc",
                    "--unshare-uts", "--unshare-cgroup-try", "--cap-drop", "ALL",
                    "--cap-add", "CAP_SETUID", "--cap-add", "CAP_SETGID"]
        # /tmp open to everyone, as a system's is: the program (as `uid`) writes its
        # temporary files there
        args += ["--die-with-parent", "--new-session", "--clearenv", "--proc", "/proc",
                 "--dev", "/dev", "--size", str(TMP_BYTES), "--perms", "1777",
                 "--tmpfs", "/tmp"]
        for name in (*SYSTEM_PATHS, *ETC_PATHS):
            path = Path(name)
            if path.is_symlink():
                args += ["--symlink", os.readlink(path), name]
            elif path.exists():
                args += ["--ro-bind", name, name]
        binds = [("--ro-bind", f) for f in _read_only(argv, self.readable, writable)]
        binds.append(("--bind", writable.resolve()))
        # the folders above them, made as bwrap would, but open to the program (bwrap copies
        # their modes: a 0700 temporary folder would shut it out)
        made: set[Path] = set()
        for _, folder in binds:
            for parent in reversed(folder.parents[:-1]):
                if parent not in made and not _is_system(parent) and parent != Path("/tmp"):
                    made.add(parent)
                    args += ["--perms", "0755", "--dir", str(parent)]
        for flag, folder in binds:
            args += [flag, str(folder), str(folder)]
        for key, value in ENV.items():
            args += ["--setenv", key, value]
        args += ["--chdir", str(cwd.resolve()), "--"]
        if self.uid is not None:
            args += [SETPRIV, f"--reuid={self.uid}", f"--regid={self.uid}", "--clear-groups",
                     "--inh-caps=-all", "--bounding-set=-all", "--no-new-privs", "--"]
        return args + argv

    def process_limit(self) -> int:
        """RLIMIT_NPROC for the program: PROCESS_LIMIT processes of its user, besides those a
        grader running as itself has already (counted here, in the parent: the child between
        fork and exec should do no more than set the number)."""
        return PROCESS_LIMIT + (0 if self.uid is not None else _processes_of(os.getuid()))

    def own(self, folder: Path) -> None:
        """Gives the folder (and what is in it) to the sandbox's user, so that the program can
        write there, and lets others enter its folders (bwrap, root without its capabilities
        by then, changes into it); nothing to do when it runs as the grader."""
        if self.uid is None:
            return
        for path in (folder, *folder.rglob("*")):
            os.lchown(path, self.uid, self.uid)
            if path.is_dir() and not path.is_symlink():
                path.chmod(path.stat().st_mode | 0o055)


def limit_processes(count: int) -> None:
    """In the child, between fork and exec: at most `count` processes of its user."""
    import resource

    resource.setrlimit(resource.RLIMIT_NPROC, (count, count))


def _processes_of(uid: int) -> int:
    count = 0
    for entry in os.scandir("/proc"):
        if entry.name.isdigit():
            try:
                count += entry.stat().st_uid == uid
            except OSError:
                continue
    return count


def _read_only(argv: list[str], extra: tuple[Path, ...], writable: Path) -> list[Path]:
    """The folders argv names that are not in the system paths and not below `writable`: the
    program's own folder, an interpreter's installation (the folder above its bin/, after
    symlinks) and a script's folder; then `extra`. Nested ones are left out (their parent
    binds them)."""
    folders: list[Path] = []
    program = shutil.which(argv[0]) if "/" not in argv[0] else argv[0]
    candidates = []
    if program:
        real = Path(program).resolve()
        candidates += [Path(program).absolute().parent, real.parent]
        if real.parent.name == "bin":
            candidates.append(real.parent.parent)
    candidates += [Path(a).resolve().parent for a in argv[1:]
                   if not a.startswith("-") and Path(a).is_file()]
    candidates += [p.resolve() for p in extra]
    inside = writable.resolve()
    for folder in candidates:
        if not folder.is_dir() or folder.is_relative_to(inside) or _is_system(folder):
            continue
        folders.append(folder)
    folders.sort(key=lambda p: len(p.parts))
    kept: list[Path] = []
    for folder in folders:
        if not any(folder.is_relative_to(k) for k in kept):
            kept.append(folder)
    return kept


def _is_system(folder: Path) -> bool:
    return any(folder.is_relative_to(p) for p in SYSTEM_PATHS)


_probed: dict[tuple[SandboxMode, tuple[Path, ...]], Sandbox | None] = {}


def sandbox_for(mode: SandboxMode, readable: tuple[Path, ...] = ()) -> Sandbox | None:
    """The sandbox for `mode`: None for off, or for auto where bubblewrap cannot run here
    (unavailable_reason says why); raises SandboxError for required where it cannot."""
    if mode == SandboxMode.OFF:
        return None
    key = (mode, readable)
    if key not in _probed:
        found, reason = _working()
        if found is None and mode == SandboxMode.REQUIRED:
            raise SandboxError(f"--sandbox required: {reason}")
        _probed[key] = None if found is None else replace(found, readable=readable)
    return _probed[key]


def unavailable_reason() -> str | None:
    """Why bubblewrap cannot sandbox a program here (not installed, user namespaces off), or
    None."""
    return _working()[1]


@functools.cache
def _working() -> tuple[Sandbox | None, str | None]:
    """The sandbox that runs `true` here, or why none does. A root grader's first choice runs
    the program as SANDBOX_UID; where that user does not exist (root of a container's user
    namespace, which maps only itself), bwrap's own user namespace, without the process limit
    (the kernel does not count root's processes)."""
    bwrap = shutil.which("bwrap")
    if bwrap is None:
        return None, "bubblewrap (bwrap) is not installed (Debian: apt-get install bubblewrap)"
    choices = [Sandbox(bwrap, None)]
    if os.geteuid() == 0 and os.access(SETPRIV, os.X_OK):
        choices.insert(0, Sandbox(bwrap, SANDBOX_UID))
    reason = None
    for choice in choices:
        reason = _probe(choice)
        if reason is None:
            return choice, None
    return None, reason


def _probe(sandbox: Sandbox) -> str | None:
    """Why `sandbox` cannot run `true`, or None."""
    import tempfile

    with tempfile.TemporaryDirectory(prefix="raycheck-sandbox-") as tmp:
        folder = Path(tmp)
        true = shutil.which("true") or "/bin/true"
        try:
            sandbox.own(folder)
            limit = functools.partial(limit_processes, sandbox.process_limit())
            run = subprocess.run(sandbox.command([true], folder, folder), preexec_fn=limit,
                                 stdin=subprocess.DEVNULL, capture_output=True, text=True,
                                 timeout=PROBE_TIMEOUT_S)
        except (OSError, subprocess.SubprocessError) as e:
            return f"bubblewrap cannot start ({e})"
    if run.returncode != 0:
        detail = run.stderr.strip().splitlines()[-1] if run.stderr.strip() else \
            f"status {run.returncode}"
        return f"bubblewrap cannot make a sandbox here ({detail}; are user namespaces off?)"
    return None
