"""Output folders built beside their final place and swapped in whole, one writer at a time:
an interrupted or failed run leaves the previous folder as it was (no stale or half-written
files, no mix of two runs), and a second run into the same folder is refused while the first
is writing."""
from __future__ import annotations

import fcntl
import os
import shutil
import tempfile
from contextlib import contextmanager
from pathlib import Path
from typing import Iterator

from raycheck.tracer.process import signals_deferred


class FolderBusy(OSError):
    """Another run is writing the same output folder."""


@contextmanager
def replaced_folder(final: Path) -> Iterator[Path]:
    """Yields an empty staging folder beside `final`; when the block ends without an
    exception the staging folder replaces `final` (the old one is removed), otherwise it is
    removed and `final` stays as it was."""
    final = Path(final)
    parent = final.resolve().parent
    parent.mkdir(parents=True, exist_ok=True)
    lock_path = parent / f".{final.name}.lock"
    with open(lock_path, "w") as lock:
        try:
            fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            raise FolderBusy(16, "another raycheck run is writing this folder",
                             str(final)) from None
        # what a run killed outright (kill -9, power loss) left behind: with the lock held no
        # other run is using these
        for stale in [*parent.glob(f".{final.name}.new-*"), *parent.glob(f".{final.name}.old-*")]:
            shutil.rmtree(stale, ignore_errors=True)
        staging: Path | None = None
        try:
            # a signal held back while the folder is made is raised at the block's end, with
            # `staging` set: the folder is removed below, never left behind
            with signals_deferred():
                staging = Path(tempfile.mkdtemp(prefix=f".{final.name}.new-", dir=parent))
            umask = os.umask(0)
            os.umask(umask)
            os.chmod(staging, 0o777 & ~umask)  # mkdtemp's 0700 would stay with the folder
            yield staging
        except BaseException:
            if staging is not None:
                shutil.rmtree(staging, ignore_errors=True)
            raise
        target = parent / final.name
        old = None
        try:
            with signals_deferred():  # Ctrl-C between the two renames would leave no folder
                if target.is_dir():
                    old = Path(tempfile.mkdtemp(prefix=f".{final.name}.old-", dir=parent))
                    os.rename(target, old / final.name)
                os.rename(staging, target)
        finally:  # also when a signal held back during the renames is raised at their end
            if old is not None:
                shutil.rmtree(old, ignore_errors=True)
    # the lock file stays: removing it would let a later run lock a new file while another
    # still holds this one
