"""Render the bundled course scenes with the tracer: `make report` until the full report exists."""
from __future__ import annotations

import time
from pathlib import Path

from tracer.cli import run as run_tracer

from .catalog import DEFAULT_SIZE, bundled


def render_gallery(out: Path, size: tuple[int, int] | None = None) -> list[tuple[str, float, Path]]:
    out.mkdir(parents=True, exist_ok=True)
    rows = []
    for scene in bundled("course"):
        w, h = size or scene.size or DEFAULT_SIZE
        lo, hi = scene.depth_range
        argv = ["-size", str(w), str(h), "-input", str(scene.path), *scene.flags,
                "-output", str(out / f"{scene.name}.png"),
                "-normals", str(out / f"{scene.name}_normals.png"),
                "-depth", str(lo), str(hi), str(out / f"{scene.name}_depth.png")]
        start = time.perf_counter()
        run_tracer(argv + ["--quiet"])
        rows.append((scene.name, time.perf_counter() - start, out / f"{scene.name}.png"))
    return rows
