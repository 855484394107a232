"""Writing output all or nothing (ReplacedFolder, write_all) under an interrupt at every moment
it can take one: a real SIGINT, which
the interrupts_raised handler turns into KeyboardInterrupt, sent from a profile function where
the interpreter checks for signals (a Python function's start or resumption, and the return of
each C call). Whatever moment it lands on, the previous output or the new one is in place,
whole, and nothing staged is left beside it."""
from __future__ import annotations

import contextlib
import gc
import os
import signal
import sys
import time
from pathlib import Path
from types import ModuleType
from typing import Callable

import pytest

from raycheck.harness.storage import staging
from raycheck.tracer import process
from raycheck.tracer.scene import outputs

# a profile function's events at the places CPython runs signal handlers: a Python frame's
# start (a generator's resumption too) and the return of a C call; a trace function's line
# events would raise where no handler can run (before a finally clause's try)
_MOMENTS = {"call", "c_return"}


def _interrupted(action: Callable[[], None], modules: list[ModuleType],
                 interrupt_at: int | None) -> int:
    """action() with SIGINT sent at moment number `interrupt_at` of the frames of `modules`,
    contextlib (the context managers' __enter__ and __exit__) and signals_deferred's module;
    the number of moments seen. Raises the KeyboardInterrupt."""
    traced = {m.__file__ for m in [*modules, contextlib, process]}
    moments = 0

    def profile(frame, event, arg):
        nonlocal moments
        if event in _MOMENTS and frame.f_code.co_filename in traced:
            if moments == interrupt_at:
                os.kill(os.getpid(), signal.SIGINT)
            moments += 1

    previous = sys.getprofile()
    sys.setprofile(profile)
    try:
        action()
    finally:
        sys.setprofile(previous)
    return moments


def _at_every_moment(make: Callable[[int], Callable[[], None]], modules: list[ModuleType],
                     check: Callable[[int], str]) -> list[tuple[bool, str]]:
    """For each moment k of make(k)'s action, the action interrupted there: whether the
    interrupt was raised, and check(k)'s account of what it left, in order."""
    moments = _interrupted(make(-1), modules, None)
    assert moments > 20  # the profile saw the calls
    outcomes = []
    umask = process.current_umask()
    for k in range(moments):
        outcomes.append(_interrupted_at(make, modules, check, k, umask))
    return outcomes


def _interrupted_at(make: Callable[[int], Callable[[], None]], modules: list[ModuleType],
                    check: Callable[[int], str], k: int, umask: int) -> tuple[bool, str]:
    """make(k)'s action interrupted at moment k: whether the interrupt was raised, and
    check(k)'s account of what it left."""
    action = make(k)
    interrupted = False
    with process.interrupts_raised():
        try:
            _interrupted(action, modules, k)
            # one that landed in a finalizer is sent again a moment later (reraising_hook)
            time.sleep(10 * process.RESEND_S)
        except KeyboardInterrupt:
            interrupted = True
    gc.collect()  # as when the command's process ends: what finalizers remove is gone
    outcome = check(k)
    assert process.current_umask() == umask, f"moment {k}: the umask was left changed"
    return interrupted, outcome


def _swapped_at_every_moment(tmp_path: Path, finishes_run: bool) -> list[tuple[bool, str]]:
    """A folder holding `previous` replaced by one holding `new`, interrupted at each moment:
    whether the interrupt was raised, and which folder is in place (the only thing left)."""
    def make(k: int) -> Callable[[], None]:
        final = tmp_path / f"run{k}" / "out"
        final.mkdir(parents=True)
        (final / "previous").write_text("previous")

        def write() -> None:
            with staging.ReplacedFolder(final, finishes_run=finishes_run) as folder:
                (folder / "new").write_text("new")
        return write

    def check(k: int) -> str:
        run = tmp_path / f"run{k}"
        left = sorted(p.name for p in run.iterdir() if not p.name.endswith(".lock"))
        assert left == ["out"], (k, left)
        contents = sorted(p.name for p in (run / "out").iterdir())
        assert contents in (["previous"], ["new"]), (k, contents)
        return contents[0]

    return _at_every_moment(make, [staging], check)


@pytest.mark.usefixtures("python_sigint_handler")  # conftest.py
def test_an_interrupt_at_any_moment_of_the_swap_leaves_one_whole_folder(tmp_path):
    """A folder that is not the command's last output (a report's comparisons, with its
    stress page to follow): the interrupt is raised wherever it lands, before the swap or
    after it (held back to its end)."""
    outcomes = _swapped_at_every_moment(tmp_path, finishes_run=False)
    assert all(raised for raised, _ in outcomes), outcomes
    assert {"previous", "new"} <= {folder for _, folder in outcomes}, outcomes


@pytest.mark.usefixtures("python_sigint_handler")  # conftest.py
def test_an_interrupt_once_the_last_folder_is_in_place_is_not_raised(tmp_path):
    """The command's outcome (finishes_run): an interrupt is raised exactly where the previous
    folder is still in place, so that status 130 means it stands; one that lands in the swap
    or after it is dropped, and the command ends with its own status."""
    outcomes = _swapped_at_every_moment(tmp_path, finishes_run=True)
    assert all(raised == (folder == "previous") for raised, folder in outcomes), outcomes
    assert {(True, "previous"), (False, "new")} <= set(outcomes), outcomes


@pytest.mark.usefixtures("python_sigint_handler")  # conftest.py
def test_an_interrupt_at_any_moment_of_writing_files_leaves_all_old_or_all_new(tmp_path):
    names = ["a.png", "b.png", "c.png"]

    def make(k: int) -> Callable[[], None]:
        run = tmp_path / f"run{k}"
        run.mkdir()
        for name in names:
            (run / name).write_text("old")
        return lambda: outputs.write_all([(run / n, lambda tmp: Path(tmp).write_text("new"))
                                          for n in names])

    def check(k: int) -> str:
        run = tmp_path / f"run{k}"
        assert sorted(p.name for p in run.iterdir()) == names, k  # no .part file left
        contents = {(run / n).read_text() for n in names}
        assert len(contents) == 1, (k, contents)
        return contents.pop()

    outcomes = _at_every_moment(make, [outputs], check)
    assert all(raised for raised, _ in outcomes), outcomes
    assert {"old", "new"} <= {contents for _, contents in outcomes}, outcomes


def _failed_swap(tmp_path: Path, monkeypatch, fails: Callable[[Path], bool]) -> Path:
    """A folder `out` holding `previous`, and a swap into it whose renames of the sources that
    `fails` picks raise ENOSPC; asserts that the swap raises it. The folder."""
    final = tmp_path / "out"
    final.mkdir()
    (final / "previous").write_text("previous")
    real_rename = os.rename

    def rename(src, dst):
        if fails(Path(src)):
            raise OSError(28, "No space left on device", str(dst))
        real_rename(src, dst)

    monkeypatch.setattr(staging.os, "rename", rename)
    try:
        with staging.ReplacedFolder(final, finishes_run=True) as folder:
            (folder / "new").write_text("new")
    except OSError as e:
        assert e.errno == 28
    else:
        raise AssertionError("the swap's failure was not raised")
    return final


def test_a_failed_swap_puts_the_previous_folder_back(tmp_path, monkeypatch):
    final = _failed_swap(tmp_path, monkeypatch, lambda src: src.name.startswith(".out.new-"))
    assert sorted(p.name for p in tmp_path.iterdir()) == [".out.lock", "out"]
    assert [p.name for p in final.iterdir()] == ["previous"]


def test_a_failed_put_back_keeps_the_previous_folder_where_it_was_moved(tmp_path, monkeypatch):
    """Both renames fail (the swap, then putting the previous folder back): the moved-aside
    folder holds the only copy of the previous output, and stays."""
    _failed_swap(tmp_path, monkeypatch, lambda src: src.name.startswith(".out.new-")
                 or src.parent.name.startswith(".out.old-"))
    kept = [p for p in tmp_path.iterdir() if p.name.startswith(".out.old-")]
    assert len(kept) == 1 and [p.name for p in (kept[0] / "out").iterdir()] == ["previous"]
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".out.new-")]


def test_a_run_killed_between_its_renames_leaves_the_previous_folder_for_the_next(tmp_path):
    """What kill -9 between the two renames leaves (the previous output in an .old- folder,
    none in place): the next run puts it back before it starts, and where that run fails it
    is in place; a stale .old- folder beside a folder in place is removed."""
    stale = tmp_path / ".out.old-abc123" / "out"
    stale.mkdir(parents=True)
    (stale / "previous").write_text("previous")
    try:
        with staging.ReplacedFolder(tmp_path / "out", finishes_run=True) as folder:
            (folder / "new").write_text("new")
            raise RuntimeError("the run fails")
    except RuntimeError:
        pass
    assert sorted(p.name for p in tmp_path.iterdir()) == [".out.lock", "out"]
    assert [p.name for p in (tmp_path / "out").iterdir()] == ["previous"]
    (tmp_path / ".out.old-def456" / "out").mkdir(parents=True)
    with staging.ReplacedFolder(tmp_path / "out", finishes_run=True) as folder:
        (folder / "new").write_text("new")
    assert sorted(p.name for p in tmp_path.iterdir()) == [".out.lock", "out"]
    assert [p.name for p in (tmp_path / "out").iterdir()] == ["new"]
