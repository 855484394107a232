"""Limits checked before any work starts, so hostile input fails fast with a clear message."""
from __future__ import annotations

from pathlib import Path

from .errors import SceneError

MAX_SCENE_BYTES = 16 * 1024 * 1024
MAX_OBJ_BYTES = 512 * 1024 * 1024
MAX_CUBEMAP_FACE_PIXELS = 8192 * 8192
MAX_NESTING = 64  # Group/Transform depth; deeper files are certainly not course scenes
MAX_COUNT = 10_000_000  # numLights / numMaterials / numObjects


def check_file_size(path: Path, limit: int, ref_path: Path, ref_line: int | None) -> None:
    size = path.stat().st_size
    if size > limit:
        raise SceneError(ref_path, ref_line,
                         f"{path} is {size} bytes, over the limit of {limit} bytes")
