"""raycheck's own Dr.Jit ray tracer reproducing the course renderer.

The public surface: `render` (Renderer, render(): a scene into float images), `options`
(RenderOptions and its settings) and `load_scene`; the subpackages are the tracer's own
(scene/: the course contract; kernel/, accel/, shade/, arithmetic/: the renderer's parts).
Names load on first use, so that importing a module of the package (the process contract,
the cache) does not load Dr.Jit."""
from __future__ import annotations

import importlib
from typing import Any

__all__ = ["load_scene", "options", "render"]


def __getattr__(name: str) -> Any:
    if name in ("options", "render"):
        return importlib.import_module(f"{__name__}.{name}")
    if name == "load_scene":
        return importlib.import_module(f"{__name__}.scene").load_scene
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
