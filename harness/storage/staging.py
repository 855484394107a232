"""Output folders built beside their final place and swapped in whole, one writer at a time:
an interrupted or failed run leaves the previous folder as it was (no stale or half-written
files, no mix of two runs), and a second run into the same folder is refused while the first
is writing."""
from __future__ import annotations

import fcntl
import os
import shutil
import tempfile
import weakref
from pathlib import Path
from typing import IO

from raycheck.tracer.process import (
    current_umask,
    finish_run,
    raise_swallowed,
    signals_deferred,
)


class FolderBusy(OSError):
    """Another run is writing the same output folder."""


class ReplacedFolder:
    """`with ReplacedFolder(final, finishes_run=...) as staging:` gives an empty staging folder
    beside `final`; when the block ends without an exception the staging folder replaces
    `final` (the old one is removed), otherwise it is removed and `final` stays as it was. A
    folder that `finishes_run` is the command's outcome: once it is in place no interrupt is
    raised (process.finish_run), so that status 130 always means the previous folder stands.

    An interrupt can be raised as any Python frame starts, a cleanup's too (or contextlib's
    __exit__ before it resumes a generator): every folder made is listed at once, with signals
    held back, and a weakref.finalize removes what is still listed when this object goes, at
    the latest when the interpreter ends."""

    def __init__(self, final: Path, *, finishes_run: bool) -> None:
        self.final = Path(final)
        self.finishes_run = finishes_run
        self.parent = self.final.resolve().parent
        self._lock: IO[str] | None = None
        self._staging: Path | None = None
        self._made: list[Path] = []
        weakref.finalize(self, _remove, self._made)

    def __enter__(self) -> Path:
        self.parent.mkdir(parents=True, exist_ok=True)
        try:
            self._lock = open(self.parent / f".{self.final.name}.lock", "w")
            try:
                fcntl.flock(self._lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except BlockingIOError:
                raise FolderBusy(16, "another raycheck run is writing this folder",
                                 str(self.final)) from None
            # what a run killed outright (kill -9, power loss) left behind: with the lock held
            # no other run is using these. Killed between its two renames, it left the previous
            # folder in an .old- folder and none in place: that one goes back first.
            target = self.parent / self.final.name
            for stale in [*self.parent.glob(f".{self.final.name}.old-*"),
                          *self.parent.glob(f".{self.final.name}.new-*")]:
                if ".old-" in stale.name and (stale / self.final.name).is_dir() \
                        and not os.path.lexists(target):
                    os.rename(stale / self.final.name, target)
                shutil.rmtree(stale, ignore_errors=True)
            staging = self._made_folder("new")
            os.chmod(staging, 0o777 & ~current_umask())  # mkdtemp's 0700 would stay with it
            self._staging = staging
        except BaseException:
            self._clean_up()
            raise
        return staging

    def __exit__(self, kind: type[BaseException] | None, *_: object) -> None:
        try:
            if kind is None:
                self._swap()
        finally:
            self._clean_up()

    def _made_folder(self, role: str) -> Path:
        # an interrupt held back while the folder is made is raised once it is listed
        with signals_deferred():
            folder = Path(tempfile.mkdtemp(prefix=f".{self.final.name}.{role}-",
                                           dir=self.parent))
            self._made.append(folder)
        return folder

    def _swap(self) -> None:
        assert self._staging is not None
        target = self.parent / self.final.name
        raise_swallowed()
        with signals_deferred():  # Ctrl-C between the two renames would leave no folder
            old = self._made_folder("old") if target.is_dir() else None
            if old is not None:
                os.rename(target, old / self.final.name)
            try:
                os.rename(self._staging, target)
            except OSError:
                if old is not None:  # the previous folder goes back, not into the bin
                    self._put_back(old, target)
                raise
            self._made.remove(self._staging)
            if self.finishes_run:
                finish_run()

    def _put_back(self, old: Path, target: Path) -> None:
        """The previous folder, moved aside into `old`, back at `target`; where that fails,
        `old` is no longer ours to remove: it holds the only copy."""
        try:
            os.rename(old / self.final.name, target)
        except OSError:
            self._made.remove(old)
            raise

    def _clean_up(self) -> None:
        """Removes the folders made and not swapped in, then lets go of the lock. An interrupt
        comes once (interrupts_raised): one that lands in the removal is followed by a whole
        one."""
        try:
            try:
                _remove(self._made)
            except BaseException:
                _remove(self._made)
                raise
        finally:
            if self._lock is not None:
                # the lock file stays: removing it would let a later run lock a new file
                # while another still holds this one
                self._lock.close()


def _remove(folders: list[Path]) -> None:
    for folder in folders:
        shutil.rmtree(folder, ignore_errors=True)
