"""raycheck's cache of work that depends only on content, shared by every process on a machine:
$RAYCHECK_CACHE, else ~/.cache/raycheck/ (where there is no home, a folder of the user's in
the temporary directory). The tracer keeps decoded cube-map faces there
(scene/cubemap.py) and its kernel loops as @dr.syntax compiled them (backend.py); the harness
its references' renders, distributions and saved benchmark (reports/runs/disk_cache.py).

Entries are files named by a digest of what they depend on, written beside and renamed into
place: a concurrent reader sees the old entry or the new, whole; a damaged entry reads as
missing; a cache that cannot be written only costs the next run the work again.
"""
from __future__ import annotations

import os
import tempfile
import zipfile
from pathlib import Path
from typing import BinaryIO, Callable

import numpy as np


def cache_folder() -> Path:
    if os.environ.get("RAYCHECK_CACHE"):
        return Path(os.environ["RAYCHECK_CACHE"])
    try:
        return Path.home() / ".cache" / "raycheck"
    except (RuntimeError, KeyError):  # no HOME and no passwd entry (some containers)
        return Path(tempfile.gettempdir()) / f"raycheck-cache-{os.getuid()}"


def load_arrays(path: Path) -> dict[str, np.ndarray] | None:
    """The arrays of an .npz entry, or None where it is missing or damaged (then redone)."""
    try:
        with np.load(path, allow_pickle=False) as data:
            return {name: data[name] for name in data.files}
    except (OSError, KeyError, ValueError, EOFError, zipfile.BadZipFile):
        return None


def save_arrays(path: Path, arrays: dict[str, np.ndarray], compress: bool = True) -> None:
    """Writes an .npz entry atomically; compress=False for entries read on every run, where
    decompressing would cost more than the disk they save."""
    _replace(path, lambda f: (np.savez_compressed if compress else np.savez)(f, **arrays))


def load_bytes(path: Path) -> bytes | None:
    try:
        return path.read_bytes()
    except OSError:
        return None


def save_bytes(path: Path, data: bytes) -> None:
    _replace(path, lambda f: f.write(data))


def _replace(path: Path, write: Callable[[BinaryIO], object]) -> None:
    """Writes an entry to a temporary file beside it and renames that into place."""
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=path.parent, suffix=path.suffix + ".tmp")
        try:
            with os.fdopen(fd, "wb") as f:
                write(f)
            os.replace(tmp, path)
        except BaseException:
            os.unlink(tmp)
            raise
    except OSError:
        pass
