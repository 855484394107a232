"""Build a submission's sources with CMake, as a teaching assistant would.

The submission's own CMakeLists.txt (at its root, else the shallowest one that makes an
executable), else raycheck's stand-in for the course starter's (starter_CMakeLists.txt:
every .cpp, one executable a2); Release. When that fails, the fixes a TA tries, in turn, each
in a fresh build folder: a newer C++ standard, then also the standard headers that old
compilers included for free (<ctime>, <cstring>, ...). The compiler is wrapped so that the
fix comes last on its command line, after whatever the project's CMakeLists set.

Every step runs as an untrusted program (CommandRenderer.run: the sandbox, limits, a time
limit). The built program is kept in a cache folder named by the sha256 of the sources
(sources.digest), with its log and a build.json: the same sources are never built twice,
and `--resume` finds them."""
from __future__ import annotations

import json
import os
import re
import shutil
import stat
import tempfile
import time
from dataclasses import asdict, dataclass, replace
from enum import StrEnum
from importlib import resources
from pathlib import Path

from ..renderers.base import RenderError
from ..renderers.command import CommandRenderer, Limits
from ..renderers.sandbox import Sandbox
from .sources import SourcesError, digest, unpack

BUILD_TIMEOUT_S = 300.0
PROGRAM = "a2"
STANDARD_HEADERS = ("cstdlib", "cstring", "ctime", "cmath", "climits", "cstdint", "algorithm",
                    "limits", "string")
FIXES: tuple[tuple[str, tuple[str, ...]], ...] = (
    ("", ()),
    ("C++17", ("-std=c++17",)),
    ("C++17 and the standard headers", ("-std=c++17",
                                        *(f"-include{h}" for h in STANDARD_HEADERS))),
)
ERROR_LINE = re.compile(r"(error|Error)[: ]")


class BuildStatus(StrEnum):
    BUILT = "built"
    FAILED = "failed"


@dataclass(frozen=True)
class BuildResult:
    status: BuildStatus
    sha256: str | None  # of the sources (None: they could not be read)
    program: str | None  # the built program (in the cache)
    fix: str  # what it needed beyond the plain build ("" none)
    template: bool  # built with raycheck's stand-in for the starter's CMakeLists.txt
    first_error: str  # the compiler's (or unpacking's) first error; "" when built
    log: str | None  # the whole build's log
    seconds: float
    cached: bool = False  # found built (the same sources, an earlier run)

    @property
    def summary(self) -> str:
        """One phrase for the class table."""
        if self.status == BuildStatus.FAILED:
            return "build failed"
        notes = [n for n in (self.fix and f"needed {self.fix}",
                             self.template and "no CMakeLists.txt: the starter's") if n]
        return "built" + (f" ({'; '.join(notes)})" if notes else "")

    def to_json(self) -> dict:
        return asdict(self)

    @classmethod
    def from_json(cls, data: dict) -> BuildResult:
        return cls(**{**data, "status": BuildStatus(data["status"])})


def build_sources(source: Path, cache: Path, sandbox: Sandbox | None,
                  jobs: int = 1) -> BuildResult:
    """Builds the submission at `source` (see sources.unpack) into cache/<sha256>/ unless it
    is there already; never raises for the submission's faults (the result says)."""
    start = time.perf_counter()
    cache.mkdir(parents=True, exist_ok=True)
    work = Path(tempfile.mkdtemp(prefix="build-", dir=cache))
    try:
        try:
            root = unpack(source, work / "src")
        except SourcesError as e:
            return BuildResult(BuildStatus.FAILED, None, None, "", False, str(e), None,
                               time.perf_counter() - start)
        sha = digest(root)
        done = cache / sha
        if (done / "build.json").is_file():
            return replace(BuildResult.from_json(json.loads((done / "build.json").read_text())),
                           cached=True)
        result, log = _attempts(root, sha, work, sandbox, jobs, start)
        return _keep(result, log, work, done)
    finally:
        shutil.rmtree(work, ignore_errors=True)


def _attempts(root: Path, sha: str, work: Path, sandbox: Sandbox | None, jobs: int,
              start: float) -> tuple[BuildResult, str]:
    project, template = _project(root)
    logs: list[str] = []
    first_error = ""
    runner = CommandRenderer(["cmake"], Limits(timeout_s=BUILD_TIMEOUT_S), name="build",
                             sandbox=sandbox)
    for k, (fix, flags) in enumerate(FIXES):
        build = work / f"build-{k}"
        build.mkdir()
        compiler = _compiler(work / f"cxx-{k}", flags)
        steps = [["cmake", "-S", str(project), "-B", str(build), "-DCMAKE_BUILD_TYPE=Release",
                  f"-DCMAKE_CXX_COMPILER={compiler}"],
                 ["cmake", "--build", str(build), "--parallel", str(jobs)]]
        logs.append(f"== attempt {k + 1}: {fix or 'as it is'}")
        failed = None
        for step in steps:
            failed = _step(runner, step, work, logs)
            if failed is not None:
                break
        program = _program(build) if failed is None else None
        if program is not None:
            return BuildResult(BuildStatus.BUILT, sha, str(program), fix, template, "", None,
                               time.perf_counter() - start), "\n".join(logs)
        if failed is None:
            failed = f"the build made no executable {PROGRAM} (nor any other)"
        # named as in the submission, not in the grader's temporary folder
        first_error = first_error or failed.replace(f"{root}/", "")
    return BuildResult(BuildStatus.FAILED, sha, None, "", template, first_error, None,
                       time.perf_counter() - start), "\n".join(logs)


def _step(runner: CommandRenderer, argv: list[str], work: Path, logs: list[str]) -> str | None:
    """Runs one build step in `work`; None when it succeeded, else its first error line."""
    logs.append("$ " + " ".join(argv))
    error = None
    try:
        runner.run(argv, work, work)
    except RenderError as e:
        error = e
    for name in ("stdout.txt", "stderr.txt"):
        path = work / name
        if path.is_file():
            logs.append(path.read_text(encoding="utf-8", errors="replace").rstrip())
    if error is None:
        return None
    output = "\n".join(logs[-2:])
    line = next((ln.strip() for ln in output.splitlines() if ERROR_LINE.search(ln)), "")
    return line[:300] or f"{argv[0]} {argv[1]}: {error}"


def _project(root: Path) -> tuple[Path, bool]:
    """The folder whose CMakeLists.txt makes the program, and whether it is raycheck's
    template (copied in, where the submission has none)."""
    if (root / "CMakeLists.txt").is_file():
        return root, False
    found = sorted((p for p in root.rglob("CMakeLists.txt")
                    if len(p.relative_to(root).parts) <= 3
                    and "add_executable" in p.read_text(encoding="utf-8", errors="replace")),
                   key=lambda p: len(p.parts))
    if found:
        return found[0].parent, False
    template = resources.files("raycheck.harness.submission") / "starter_CMakeLists.txt"
    (root / "CMakeLists.txt").write_text(template.read_text(encoding="utf-8"),
                                          encoding="utf-8")
    return root, True


def _compiler(path: Path, flags: tuple[str, ...]) -> Path:
    """A compiler that is the system's C++ compiler with `flags` last on its command line."""
    cxx = shutil.which("g++") or shutil.which("c++") or "c++"
    quoted = " ".join(f"'{f}'" for f in flags)
    path.write_text(f'#!/bin/sh\nexec {cxx} "$@" {quoted}\n', encoding="utf-8")
    path.chmod(0o755)
    return path


def _program(build: Path) -> Path | None:
    """The built executable: one named a2, else the only executable file the build made."""
    found = [p for p in build.rglob("*") if p.is_file() and "CMakeFiles" not in p.parts
             and os.access(p, os.X_OK) and _is_elf(p)]
    named = [p for p in found if p.name == PROGRAM]
    if named:
        return named[0]
    return found[0] if len(found) == 1 else None


def _is_elf(path: Path) -> bool:
    with open(path, "rb") as f:
        return f.read(4) == b"\x7fELF"


def _keep(result: BuildResult, log: str, work: Path, done: Path) -> BuildResult:
    """Moves the program and the log into `done` (a folder named by the sources' sha256),
    all at once: a concurrent build of the same sources keeps the first one there."""
    staging = Path(tempfile.mkdtemp(prefix="keep-", dir=done.parent))
    staging.chmod(0o755)  # the sandbox's user runs the program from here
    (staging / "build.log").write_text(log, encoding="utf-8")
    program = None
    if result.program is not None:
        program = staging / PROGRAM
        shutil.copyfile(result.program, program)
        program.chmod(stat.S_IRWXU | stat.S_IRGRP | stat.S_IXGRP | stat.S_IROTH | stat.S_IXOTH)
    kept = BuildResult(result.status, result.sha256,
                       str(done / PROGRAM) if program else None, result.fix, result.template,
                       result.first_error, str(done / "build.log"), result.seconds)
    (staging / "build.json").write_text(json.dumps(kept.to_json(), indent=1), encoding="utf-8")
    try:
        staging.rename(done)
    except OSError:  # built meanwhile by another worker: theirs stands
        shutil.rmtree(staging, ignore_errors=True)
        return BuildResult.from_json(json.loads((done / "build.json").read_text()))
    return kept
