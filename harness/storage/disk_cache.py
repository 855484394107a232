"""The harness's part of raycheck's per-machine cache (tracer/cache.py: where it is, how
entries are written and read): the reference's distributions (distribution.py), their prepared
statistics, the references' renders (case.cached_role) and the saved benchmark run
(commands/report.py).

Keys name what the result depends on: the scene's and assets' bytes, the request, the
renderer's identity (raycheck's version) and engine_digest(), the content of the engines'
source, so that an edited renderer misses instead of serving what the old code rendered.
"""
from __future__ import annotations

import hashlib
from functools import lru_cache
from pathlib import Path

from raycheck.tracer.cache import cache_folder, load_arrays, load_bytes, save_arrays, save_bytes

__all__ = ["cache_folder", "engine_digest", "load_arrays", "load_bytes", "save_arrays",
           "save_bytes"]


@lru_cache(maxsize=1)
def engine_digest() -> str:
    """sha256 of the Python source of both renderers and of how the harness drives them
    (tracer/, mitsuba_ref/, harness/renderers/): what a cached render or timing depends on
    beyond its inputs. Other harness code (pages, metrics) does not change a render. The
    packages are found, not imported: importing mitsuba_ref loads Mitsuba (0.25 s), which a
    check against the tracer never uses."""
    from importlib.util import find_spec

    h = hashlib.sha256()
    for package in ("raycheck.tracer", "raycheck.mitsuba_ref", "raycheck.harness.renderers"):
        spec = find_spec(package)
        assert spec is not None and spec.origin is not None  # raycheck's own, installed
        root = Path(spec.origin).resolve().parent
        for path in sorted(root.rglob("*.py")):
            h.update(path.relative_to(root).as_posix().encode() + b"\0")
            h.update(path.read_bytes() + b"\0")
    return h.hexdigest()
