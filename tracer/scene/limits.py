"""Limits checked before any work starts, so hostile input fails fast with a clear message."""
from __future__ import annotations

from pathlib import Path

from .errors import SceneError

MAX_SCENE_BYTES = 16 * 1024 * 1024
MAX_OBJ_BYTES = 512 * 1024 * 1024
MAX_CUBEMAP_FACE_PIXELS = 8192 * 8192
MAX_CUBEMAP_FACE_BYTES = 256 * 1024 * 1024
MAX_NESTING = 64  # Group/Transform depth; deeper files are certainly not course scenes
MAX_COUNT = 10_000_000  # numLights / numMaterials / numObjects (numLights: MAX_LIGHTS below)
# Every light, sphere and plane is unrolled into the render kernel, whose compile time grows
# faster than linearly (on one CPU core: 1000 spheres ~13 s, 4000 spheres > 5 min; 1000 point
# lights with -shadows ~140 s), so a 16 MiB file of spheres would never finish. Meshes and
# Triangle objects go through the BVH instead and are limited only by MAX_TRIANGLES.
MAX_LIGHTS = 256
MAX_SPHERES_PLANES = 1000
MAX_TRIANGLES = 1 << 24  # the BVH is built for up to 2^24 triangles (bvh.MEDIAN_DEPTH)
MAX_OBJ_VERTICES = 1 << 25
# Render requests, the same for both renderers (part of the shared command-line contract)
MAX_SIDE = 16384
MAX_SUBPIXELS = 1 << 28  # width*height, times 9 with -filter
MAX_BOUNCES = 64
MAX_SAMPLES = 4096


def check_file_size(path: Path, limit: int, ref_path: Path, ref_line: int | None) -> None:
    try:
        size = path.stat().st_size
    except (OSError, ValueError) as e:
        raise SceneError(ref_path, ref_line, f"cannot read {path}: {e}") from None
    if size > limit:
        what = "the file" if path == ref_path else str(path)
        raise SceneError(ref_path, ref_line,
                         f"{what} is {size} bytes, over the limit of {limit} bytes")


def request_problem(width: int, height: int, filter: bool, bounces: int,
                    samples: int) -> str | None:
    """What is wrong with a render request's size, bounces or samples, or None; each renderer
    raises its own error with the message."""
    if not (1 <= width <= MAX_SIDE and 1 <= height <= MAX_SIDE):
        return f"image size {width}x{height} is outside 1..{MAX_SIDE} per side"
    sub = width * height * (9 if filter else 1)
    if sub > MAX_SUBPIXELS:
        return (f"image size {width}x{height} needs {sub} samples per pass, over the limit of "
                f"{MAX_SUBPIXELS}")
    if not 0 <= bounces <= MAX_BOUNCES:
        return f"bounces {bounces} is outside 0..{MAX_BOUNCES}"
    if not 1 <= samples <= MAX_SAMPLES:
        return f"samples {samples} is outside 1..{MAX_SAMPLES}"
    return None
