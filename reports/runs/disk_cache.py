"""The harness's cache of work that depends only on content, shared by every run on a machine:
$RAYCHECK_CACHE, else ~/.cache/raycheck/. It holds the reference's distributions
(distribution.py), their prepared statistics, the references' renders (case.cached_role) and
the saved benchmark run (cli/report.py).

Keys name what the result depends on: the scene's and assets' bytes, the request, the
renderer's identity (raycheck's version) and engine_digest(), the content of the engines'
source, so that an edited renderer misses instead of serving what the old code rendered.
Entries are written beside and renamed into place: a concurrent reader sees the old entry or
the new, whole; a cache that cannot be written only costs the next run the work again.
"""
from __future__ import annotations

import hashlib
import os
import tempfile
from functools import lru_cache
from pathlib import Path

import numpy as np


def cache_folder() -> Path:
    return Path(os.environ.get("RAYCHECK_CACHE") or Path.home() / ".cache" / "raycheck")


@lru_cache(maxsize=1)
def engine_digest() -> str:
    """sha256 of the Python source of both renderers and of how the harness drives them
    (tracer/, mitsuba_ref/, reports/renderers/): what a cached render or timing depends on
    beyond its inputs. Other harness code (pages, metrics) does not change a render."""
    import raycheck.mitsuba_ref
    import raycheck.tracer

    from .. import renderers

    h = hashlib.sha256()
    for package in (raycheck.tracer, raycheck.mitsuba_ref, renderers):
        root = Path(package.__file__).resolve().parent
        for path in sorted(root.rglob("*.py")):
            h.update(path.relative_to(root).as_posix().encode() + b"\0")
            h.update(path.read_bytes() + b"\0")
    return h.hexdigest()


def load_arrays(path: Path) -> dict[str, np.ndarray] | None:
    """The arrays of an .npz entry, or None where it is missing or damaged (then redone)."""
    try:
        with np.load(path, allow_pickle=False) as data:
            return {name: data[name] for name in data.files}
    except (OSError, KeyError, ValueError, EOFError):
        return None


def save_arrays(path: Path, arrays: dict[str, np.ndarray], compress: bool = True) -> None:
    """Writes an .npz entry atomically; compress=False for entries read on every run, where
    decompressing would cost more than the disk they save."""
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=path.parent, suffix=".npz.tmp")
        try:
            with os.fdopen(fd, "wb") as f:
                (np.savez_compressed if compress else np.savez)(f, **arrays)
            os.replace(tmp, path)
        except BaseException:
            os.unlink(tmp)
            raise
    except OSError:
        pass
