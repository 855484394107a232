"""Writing a command's output files all or nothing (the course command line's contract: no
half-written output files). Shared by both renderers' command lines: this is file plumbing, not
image output; each side quantises its images with its own code."""
from __future__ import annotations

import os
import tempfile
from pathlib import Path
from typing import Callable


def write_all(files: list[tuple[Path, Callable[[str], None]]]) -> None:
    """Write several files all or nothing: each through a temporary file in its own folder,
    and only when every one is complete are they renamed to their names. A failed or
    interrupted write leaves no half-written file and no new file at all, and every existing
    file under those names untouched. (A rename itself can only fail for reasons the command
    line checks beforehand, such as a name that is a folder.)"""
    staged: list[tuple[str, Path]] = []
    umask = os.umask(0)
    os.umask(umask)
    try:
        for path, write in files:
            path = Path(path)
            folder = path.parent if str(path.parent) else Path(".")
            try:
                fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".part", dir=folder)
                os.close(fd)
                staged.append((tmp, path))
                write(tmp)
                os.chmod(tmp, 0o666 & ~umask)  # mkstemp makes it 0600; give it open()'s mode
            except OSError as e:  # name the file asked for, not the temporary one
                raise OSError(e.errno, e.strerror or str(e), str(path)) from None
        while staged:
            tmp, path = staged[0]
            os.replace(tmp, path)
            staged.pop(0)
    finally:
        for tmp, _ in staged:
            try:
                os.unlink(tmp)
            except OSError:
                pass
