"""raycheck's per-machine cache keeps at most $RAYCHECK_CACHE_SIZE bytes (tracer/cache.py):
the least recently used entries go first, a read renews an entry, a write prunes when no
process has within PRUNE_INTERVAL, and only files named like the cache's own are touched."""
from __future__ import annotations

import os
import subprocess
import sys
import time
import zipfile
from pathlib import Path

import numpy as np
import pytest

from raycheck.tracer import cache as tracer_cache
from raycheck.tracer.cache import (
    PRUNE_INTERVAL,
    STALE_TEMPORARY,
    STAMP,
    CacheSettingError,
    Pruned,
    prune,
    size_limit,
)

NOW = 2_000_000_000.0


@pytest.fixture
def cache(tmp_path: Path, monkeypatch) -> Path:
    monkeypatch.setenv("RAYCHECK_CACHE", str(tmp_path / "cache"))
    monkeypatch.delenv("RAYCHECK_CACHE_SIZE", raising=False)
    (tmp_path / "cache").mkdir()
    return tmp_path / "cache"


def entry(folder: Path, name: str, size: int, mtime: float) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / name
    path.write_bytes(b"x" * size)
    os.utime(path, (mtime, mtime))
    return path


def names(cache: Path) -> set[str]:
    return {p.relative_to(cache).as_posix() for p in cache.rglob("*") if p.is_file()}


@pytest.mark.parametrize("text, expected", [
    ("", 2 << 30), ("0", 0), (" 123 ", 123), ("500M", 500 << 20), ("2g", 2 << 30),
    ("2GB", 2 << 30), ("3KiB", 3072), ("1T", 1 << 40)])
def test_size_limit_reads_whole_numbers_with_binary_units(monkeypatch, text, expected):
    monkeypatch.setenv("RAYCHECK_CACHE_SIZE", text)
    assert size_limit() == expected


@pytest.mark.parametrize("text", ["abc", "1.5G", "-1", "2X", "G"])
def test_size_limit_refuses_what_is_not_a_size(monkeypatch, text):
    monkeypatch.setenv("RAYCHECK_CACHE_SIZE", text)
    with pytest.raises(CacheSettingError, match="RAYCHECK_CACHE_SIZE="):
        size_limit()


def test_prune_removes_the_least_recently_used_entries_until_the_rest_fit(cache: Path):
    hexa, hexb, hexc, hexd = ("a" * 64, "b" * 64, "c" * 32, "d" * 64)
    entry(cache, f"{hexa}.npz", 400, NOW - 40)                       # oldest
    entry(cache / "renders", f"{hexb}.npz", 300, NOW - 30)
    entry(cache / "syntax", f"{hexc}.marshal", 200, NOW - 20)
    entry(cache / "prepared", f"{hexd}-{'e' * 16}.npz", 100, NOW - 10)  # newest
    # 1000 bytes in all: without the oldest 600 > 500, without the next 300 fit
    assert prune(500, NOW) == Pruned(removed=2, kept_bytes=300)
    assert names(cache) == {f"syntax/{hexc}.marshal", f"prepared/{hexd}-{'e' * 16}.npz"}
    assert prune(300, NOW) == Pruned(removed=0, kept_bytes=300)


def test_prune_leaves_files_that_are_not_entries_and_temporaries_being_written(cache: Path):
    foreign = {"notes.txt", "abc.npz", "sub/readme.md", f"deep/er/{'f' * 64}.npz"}
    for name in foreign:
        entry(cache / Path(name).parent, Path(name).name, 100, NOW - 1e6)
    entry(cache, STAMP, 0, NOW - 1e6)
    entry(cache, "tmpk3_x9a1q.npz.tmp", 100, NOW - STALE_TEMPORARY + 60)   # being written
    entry(cache / "renders", "tmpzz81b2c0.json.tmp", 100, NOW - STALE_TEMPORARY - 60)  # left
    assert prune(0, NOW) == Pruned(removed=1, kept_bytes=0)
    assert names(cache) == foreign | {STAMP, "tmpk3_x9a1q.npz.tmp"}


def test_a_read_renews_an_entry(cache: Path):
    now = time.time()
    old, mid, new = (cache / f"{c * 64}.npz" for c in "abc")
    for k, path in enumerate((old, mid, new)):
        tracer_cache.save_arrays(path, {"v": np.arange(64, dtype=np.float32)}, compress=False)
        os.utime(path, (now - 30 + 10 * k,) * 2)
    size = old.stat().st_size
    assert tracer_cache.load_arrays(old)["v"][63] == 63
    assert old.stat().st_mtime >= now  # the read's time, after the others'
    prune(2 * size, time.time())
    assert names(cache) == {STAMP, old.name, new.name}


def test_a_write_prunes_when_no_process_has_within_the_interval(cache: Path, monkeypatch):
    monkeypatch.setenv("RAYCHECK_CACHE_SIZE", "1000")
    now = time.time()
    x, y, b, c, d = (f"{ch * 64}.json" for ch in "01bcd")
    entry(cache, x, 600, now - 100)
    tracer_cache.save_bytes(cache / b, b"b" * 600)  # no stamp yet: prunes; x is older than b
    assert names(cache) == {STAMP, b}
    os.utime(cache / b, (now - 50,) * 2)
    entry(cache, y, 600, now - 200)
    tracer_cache.save_bytes(cache / c, b"c" * 600)  # pruned just now: none
    assert names(cache) == {STAMP, b, c, y}
    os.utime(cache / c, (now - 40,) * 2)
    stamp_time = now - PRUNE_INTERVAL - 1
    os.utime(cache / STAMP, (stamp_time, stamp_time))
    tracer_cache.save_bytes(cache / d, b"d" * 600)  # the interval has passed: y, b, c go
    assert names(cache) == {STAMP, d}
    assert (cache / STAMP).stat().st_mtime > stamp_time


def test_a_command_refuses_a_bad_size_before_it_starts(tmp_path: Path):
    scene = Path(__file__).parents[2] / "scenes" / "features" / "triangle.txt"
    out = tmp_path / "a.png"
    env = {**os.environ, "RAYCHECK_CACHE_SIZE": "lots"}
    proc = subprocess.run([sys.executable, "-m", "raycheck.tracer", "-input", str(scene),
                           "-size", "4", "4", "-output", str(out)],
                          capture_output=True, text=True, env=env)
    assert proc.returncode == 2
    assert proc.stderr == ("python -m raycheck.tracer: error: RAYCHECK_CACHE_SIZE='lots' is not "
                           "a size (a whole number of bytes, or of K, M, G or T: 500M, 2G)\n")
    assert not out.exists()
    # a help text needs no cache, and every command's --help shows it whatever the setting
    for command in (["raycheck.tracer"], ["raycheck.harness", "render"],
                    ["raycheck.mitsuba_ref"], ["raycheck.harness", "check"]):
        proc = subprocess.run([sys.executable, "-m", *command, "--help"],
                              capture_output=True, text=True, env=env)
        assert (proc.returncode, proc.stderr) == (0, ""), command
        assert proc.stdout.startswith("usage:"), command


@pytest.mark.parametrize("compress", [True, False])
def test_saved_arrays_load_as_they_were(cache: Path, compress: bool):
    arrays = {"bytes": np.arange(4 * 5 * 3, dtype=np.uint8).reshape(4, 5, 3),
              "share": np.array([0.25, np.nan, -0.0], dtype=np.float32),
              "meta": np.array('{"seconds": 1.5}')}
    path = cache / f"{'9' * 64}.npz"
    tracer_cache.save_arrays(path, arrays, compress=compress)
    loaded = tracer_cache.load_arrays(path)
    assert loaded.keys() == arrays.keys()
    for name, value in arrays.items():
        assert loaded[name].dtype == value.dtype and loaded[name].shape == value.shape
        assert loaded[name].tobytes() == value.tobytes()
    with zipfile.ZipFile(path) as z:
        methods = {info.compress_type for info in z.infolist()}
    assert methods == {zipfile.ZIP_DEFLATED if compress else zipfile.ZIP_STORED}
