"""raycheck's cache of work that depends only on content, shared by every process on a machine:
$RAYCHECK_CACHE, else ~/.cache/raycheck/ (where there is no home, a folder of the user's in
the temporary directory). The tracer keeps decoded cube-map faces there
(scene/cubemap.py) and its kernel loops as @dr.syntax compiled them (backend.py); the harness
its references' renders, distributions and saved benchmark (harness/storage/disk_cache.py).

Entries are files named by a digest of what they depend on, written beside and renamed into
place: a concurrent reader sees the old entry or the new, whole; a damaged entry reads as
missing; a cache that cannot be written only costs the next run the work again.

The cache holds at most $RAYCHECK_CACHE_SIZE bytes (default 2G; K, M, G, T are powers of 1024)
after a prune: the least recently used entries go first (a read counts as a use: it renews the
entry's modification time). A process that writes an entry prunes the cache when no process
on the machine has done so for PRUNE_INTERVAL seconds, so the cache can pass its size by what
is written in that time. Every engine change keys new entries (disk_cache.engine_digest), so
without the bound the old ones stayed forever: 4.0 GB on the development machine.
"""
from __future__ import annotations

import os
import re
import tempfile
import time
import zipfile
import zlib
from dataclasses import dataclass
from pathlib import Path
from typing import BinaryIO, Callable, Iterator

import numpy as np

SIZE_VARIABLE = "RAYCHECK_CACHE_SIZE"
DEFAULT_SIZE = 2 << 30
PRUNE_INTERVAL = 600.0  # seconds; a scan of 8,670 entries took 62-65 ms
STALE_TEMPORARY = 3600.0  # seconds: older temporary files are left by killed processes
STAMP = ".pruned"  # its modification time is the last prune's
# Only files named like the cache's own are counted and removed, in the folder and its
# subfolders, one level deep: $RAYCHECK_CACHE may name a folder that holds other files too.
_ENTRY = re.compile(r"[0-9a-f]{16,}(-[0-9a-f]+)?\.(npz|json|marshal)")
_TEMPORARY = re.compile(r"tmp\w+\.(npz|json|marshal)\.tmp")
_UNITS = {"": 1, "K": 1 << 10, "M": 1 << 20, "G": 1 << 30, "T": 1 << 40}


class CacheSettingError(ValueError):
    """$RAYCHECK_CACHE_SIZE is not a size (one-line message)."""


def cache_folder() -> Path:
    if os.environ.get("RAYCHECK_CACHE"):
        return Path(os.environ["RAYCHECK_CACHE"])
    try:
        return Path.home() / ".cache" / "raycheck"
    except (RuntimeError, KeyError):  # no HOME and no passwd entry (some containers)
        return Path(tempfile.gettempdir()) / f"raycheck-cache-{os.getuid()}"


def size_limit() -> int:
    """The cache's size bound in bytes, from $RAYCHECK_CACHE_SIZE (commands check it before
    they start: process.run_command)."""
    text = os.environ.get(SIZE_VARIABLE, "").strip()
    if not text:
        return DEFAULT_SIZE
    match = re.fullmatch(r"(\d+)\s*([KMGT]?)(?:i?B)?", text, re.IGNORECASE)
    if match is None:
        raise CacheSettingError(f"{SIZE_VARIABLE}={text!r} is not a size (a whole number of "
                                "bytes, or of K, M, G or T: 500M, 2G)")
    return int(match[1]) * _UNITS[match[2].upper()]


@dataclass(frozen=True)
class Pruned:
    removed: int  # entries (and stale temporary files) removed
    kept_bytes: int  # what the entries left hold


def prune(limit: int, now: float | None = None) -> Pruned:
    """Removes the least recently used entries until the rest hold at most `limit` bytes, and
    temporary files older than STALE_TEMPORARY. Another process may be reading an entry
    removed here: it reads it whole (POSIX keeps an open file) or finds it missing and
    makes it again."""
    now = time.time() if now is None else now
    entries: list[tuple[float, int, str]] = []
    removed = 0
    for item in _cache_files():
        try:
            st = item.stat(follow_symlinks=False)
        except OSError:
            continue
        if _TEMPORARY.fullmatch(item.name):
            if now - st.st_mtime > STALE_TEMPORARY:
                removed += _unlink(item.path)
        elif _ENTRY.fullmatch(item.name):
            entries.append((st.st_mtime, st.st_size, item.path))
    total = sum(size for _, size, _ in entries)
    for _, size, path in sorted(entries):
        if total <= limit:
            break
        if _unlink(path):
            removed += 1
            total -= size
    return Pruned(removed, total)


def _cache_files() -> Iterator[os.DirEntry]:
    try:
        top = list(os.scandir(cache_folder()))
    except OSError:
        return
    for item in top:
        if item.is_dir(follow_symlinks=False):
            try:
                yield from (sub for sub in os.scandir(item.path)
                            if sub.is_file(follow_symlinks=False))
            except OSError:
                continue
        elif item.is_file(follow_symlinks=False):
            yield item


def _unlink(path: str) -> bool:
    try:
        os.unlink(path)
        return True
    except OSError:
        return False


def _prune_when_due() -> None:
    """After a write: a prune, unless any process pruned within PRUNE_INTERVAL. The stamp is
    renewed before the scan, so that processes writing at once seldom scan twice."""
    stamp = cache_folder() / STAMP
    now = time.time()
    try:
        if now - stamp.stat().st_mtime < PRUNE_INTERVAL:
            return
    except OSError:
        pass  # no stamp yet: never pruned
    try:
        stamp.touch()
        limit = size_limit()
    except (OSError, CacheSettingError):  # a read-only cache; a size the command reported
        return
    prune(limit, now)


def _used(path: Path) -> None:
    """Marks an entry as recently used for prune (a cache on a read-only disk stays as is)."""
    try:
        os.utime(path)
    except OSError:
        pass


def load_arrays(path: Path) -> dict[str, np.ndarray] | None:
    """The arrays of an .npz entry, or None where it is missing or damaged (then redone)."""
    try:
        with np.load(path, allow_pickle=False) as data:
            arrays = {name: data[name] for name in data.files}
    except (OSError, KeyError, ValueError, EOFError, zipfile.BadZipFile, zlib.error):
        return None
    _used(path)
    return arrays


def save_arrays(path: Path, arrays: dict[str, np.ndarray], compress: bool = True) -> None:
    """Writes an .npz entry atomically; compress=False for entries read on every run, where
    decompressing would cost more than the disk they save."""
    _replace(path, lambda f: _write_npz(f, arrays, compress))


def _write_npz(f: BinaryIO, arrays: dict[str, np.ndarray], compress: bool) -> None:
    """np.savez(_compressed)'s file, compressed at zlib level 3 rather than 6: a report's
    distributions and renders (8-bit images) 3.8x faster for 8% more bytes (3.5 s -> 0.9 s,
    25.2 -> 27.3 MB on 60 entries)."""
    method = zipfile.ZIP_DEFLATED if compress else zipfile.ZIP_STORED
    with zipfile.ZipFile(f, "w", method, compresslevel=3 if compress else None) as z:
        for name, value in arrays.items():
            with z.open(f"{name}.npy", "w", force_zip64=True) as member:
                np.lib.format.write_array(member, np.asanyarray(value), allow_pickle=False)


def load_bytes(path: Path) -> bytes | None:
    """The bytes of an entry, or None where it is missing."""
    try:
        data = path.read_bytes()
    except OSError:
        return None
    _used(path)
    return data


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
        return
    _prune_when_due()
