"""Render the bundled course scenes with the tracer: `make report` until the full report exists."""
from __future__ import annotations

import time
from pathlib import Path

from raycheck.tracer.cli import run as run_tracer
from raycheck.tracer.scene.request import KINDS

from ..catalog import DEFAULT_SIZE, bundled


def render_gallery(out: Path, size: tuple[int, int] | None = None) -> list[tuple[str, float, Path]]:
    out.mkdir(parents=True, exist_ok=True)
    rows = []
    for scene in bundled("course"):
        request = scene.typical_request(size or scene.size or DEFAULT_SIZE).with_kinds(KINDS)
        argv = request.to_argv(scene.path, {
            "color": out / f"{scene.name}.png", "normals": out / f"{scene.name}_normals.png",
            "depth": out / f"{scene.name}_depth.png"})
        start = time.perf_counter()
        run_tracer(argv + ["--quiet"])
        rows.append((scene.name, time.perf_counter() - start, out / f"{scene.name}.png"))
    return rows
