"""The starter-shaped C++ solution of the assignment (tests/solution_cpp/, written from
docs/course-format.md): built once per set of sources into raycheck's cache, and copied with a
mistake written into its C++ for tests that need a real program with a known slip."""
from __future__ import annotations

import shutil
from dataclasses import dataclass
from pathlib import Path

from raycheck.harness.submission.cmake import BuildStatus, build_sources
from raycheck.tracer.cache import cache_folder

SOLUTION = Path(__file__).resolve().parent / "solution_cpp"


@dataclass(frozen=True)
class Edit:
    """One slip written into the solution: `old`, which must occur exactly once in `file`
    (relative to the solution), becomes `new`."""

    file: str
    old: str
    new: str


def copy_solution(dest: Path, edits: tuple[Edit, ...] = ()) -> Path:
    """The solution's sources in `dest` (made), with `edits` applied."""
    shutil.copytree(SOLUTION, dest, ignore=shutil.ignore_patterns("build*", "CMakeFiles"))
    for edit in edits:
        path = dest / edit.file
        text = path.read_text()
        assert text.count(edit.old) == 1, f"{edit.old!r} is not once in {edit.file}"
        path.write_text(text.replace(edit.old, edit.new))
    return dest


def build_solution(source: Path = SOLUTION) -> Path:
    """The program built from `source` (a solution or an edited copy), from the cache where
    the same sources were built before."""
    result = build_sources(source, cache_folder() / "solution-builds", None, jobs=2)
    assert result.status == BuildStatus.BUILT and result.program, result.first_error
    return Path(result.program)
