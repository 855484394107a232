"""A submission's sources, from what a teacher has: a folder, a .zip, a .tar(.gz|.bz2|.xz),
or a git repository (a folder holding .git, or a bundle file; cloned locally, never from a
network). Unpacked into a folder of the grader's, within limits checked as it goes (no file
outside that folder, no links, at most MAX_FILES files and MAX_BYTES bytes), and named by
the sha256 of their contents, so that a rebuild of the same sources is found in the cache."""
from __future__ import annotations

import hashlib
import os
import shutil
import stat
import subprocess
import tarfile
import zipfile
from pathlib import Path

MAX_FILES = 20_000
MAX_BYTES = 512 << 20
ARCHIVES = (".zip", ".tar", ".tar.gz", ".tgz", ".tar.bz2", ".tar.xz")
SOURCE_SUFFIXES = (".cpp", ".cc", ".cxx", ".h", ".hpp")
# what a digest leaves out: a build's outputs and version control, which change without the
# program changing
SKIPPED = (".git", "build", "cmake-build-debug", "cmake-build-release", "CMakeFiles")
GIT_TIMEOUT_S = 120


class SourcesError(ValueError):
    """Sources that cannot be unpacked (the submission's row says why)."""


def is_sources(path: Path) -> bool:
    """Whether `path` is a submission given as sources (not a program to run)."""
    if path.is_file():
        return path.name.endswith(ARCHIVES) or path.suffix == ".bundle"
    if not path.is_dir():
        return False
    if (path / ".git").exists() or (path / "CMakeLists.txt").is_file():
        return True
    return any(p.suffix in SOURCE_SUFFIXES for p in _walk(path))


def unpack(path: Path, into: Path) -> Path:
    """The sources of `path` under `into` (made here, empty); returns their root: the one
    folder an archive holds, if it holds nothing else."""
    into.mkdir(parents=True)
    if path.is_dir() and not (path / ".git").exists():
        _copy_tree(path, into)
    elif path.is_dir() or path.suffix == ".bundle":
        _clone(path, into)
    elif path.name.endswith(".zip"):
        _unzip(path, into)
    else:
        _untar(path, into)
    entries = [e for e in into.iterdir() if e.name not in ("__MACOSX", ".DS_Store")]
    if len(entries) == 1 and entries[0].is_dir() and not (into / "CMakeLists.txt").exists():
        return entries[0]
    return into


def digest(root: Path) -> str:
    """sha256 over the sources' relative paths and contents, in sorted order."""
    h = hashlib.sha256()
    for path in sorted(_walk(root)):
        h.update(str(path.relative_to(root)).encode() + b"\0")
        h.update(hashlib.sha256(path.read_bytes()).digest())
    return h.hexdigest()


def _walk(root: Path):
    for folder, dirs, files in os.walk(root):
        dirs[:] = sorted(d for d in dirs if d not in SKIPPED and not d.startswith("build"))
        for name in files:
            path = Path(folder) / name
            if path.is_file() and not path.is_symlink():
                yield path


class _Budget:
    def __init__(self, source: Path) -> None:
        self.source = source
        self.files = 0
        self.bytes = 0

    def take(self, size: int) -> None:
        self.files += 1
        self.bytes += size
        if self.files > MAX_FILES:
            raise SourcesError(f"{self.source}: more than {MAX_FILES} files")
        if self.bytes > MAX_BYTES:
            raise SourcesError(f"{self.source}: more than {MAX_BYTES >> 20} MiB of files")


def _copy_tree(source: Path, into: Path) -> None:
    budget = _Budget(source)
    for folder, dirs, files in os.walk(source):
        dirs[:] = [d for d in dirs if not (Path(folder) / d).is_symlink()]
        rel = Path(folder).relative_to(source)
        (into / rel).mkdir(parents=True, exist_ok=True)
        for name in files:
            path = Path(folder) / name
            if path.is_symlink() or not path.is_file():
                continue
            budget.take(path.stat().st_size)
            shutil.copyfile(path, into / rel / name)


def _inside(into: Path, name: str, source: Path) -> Path:
    target = (into / name).resolve()
    if not target.is_relative_to(into.resolve()):
        raise SourcesError(f"{source}: {name!r} would land outside the submission's folder")
    return target


def _unzip(source: Path, into: Path) -> None:
    budget = _Budget(source)
    try:
        with zipfile.ZipFile(source) as archive:
            for info in archive.infolist():
                target = _inside(into, info.filename, source)
                if info.is_dir():
                    target.mkdir(parents=True, exist_ok=True)
                    continue
                if stat.S_ISLNK(info.external_attr >> 16):
                    continue  # a link could point anywhere: sources do not need one
                budget.take(info.file_size)
                target.parent.mkdir(parents=True, exist_ok=True)
                with archive.open(info) as data, open(target, "wb") as out:
                    shutil.copyfileobj(data, out)
    except (zipfile.BadZipFile, zipfile.LargeZipFile, EOFError, NotImplementedError) as e:
        raise SourcesError(f"{source}: not a readable zip ({e})") from None


def _untar(source: Path, into: Path) -> None:
    budget = _Budget(source)
    try:
        with tarfile.open(source) as archive:
            members = []
            for member in archive:
                if not (member.isfile() or member.isdir()):
                    continue  # links, devices, fifos: sources do not need them
                _inside(into, member.name, source)
                if member.isfile():
                    budget.take(member.size)
                members.append(member)
            archive.extractall(into, members=members, filter="data")
    except (tarfile.TarError, EOFError, OSError) as e:
        raise SourcesError(f"{source}: not a readable tar archive ({e})") from None


def _clone(source: Path, into: Path) -> None:
    """A local clone (a repository folder or a bundle file) of its checked-out branch; no
    hooks, no network (protocols other than a local file refused)."""
    into.rmdir()
    env = {"PATH": os.environ.get("PATH", "/usr/bin:/bin"), "GIT_TERMINAL_PROMPT": "0",
           "GIT_ALLOW_PROTOCOL": "file", "GIT_CONFIG_NOSYSTEM": "1", "HOME": str(into.parent)}
    try:
        run = subprocess.run(["git", "clone", "--quiet", "--no-hardlinks", "--depth", "1",
                              "--", f"file://{source.resolve()}" if source.is_dir()
                              else str(source.resolve()), str(into)],
                             env=env, stdin=subprocess.DEVNULL, capture_output=True, text=True,
                             timeout=GIT_TIMEOUT_S)
    except (OSError, subprocess.TimeoutExpired) as e:
        raise SourcesError(f"{source}: git clone failed ({e})") from None
    if run.returncode != 0:
        last = (run.stderr.strip().splitlines() or [f"status {run.returncode}"])[-1]
        raise SourcesError(f"{source}: git clone failed ({last})")
    shutil.rmtree(into / ".git", ignore_errors=True)
    budget = _Budget(source)
    for path in _walk(into):
        budget.take(path.stat().st_size)
