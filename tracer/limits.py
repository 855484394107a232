"""Render limits, checked before any work starts."""
from __future__ import annotations

MAX_SIDE = 16384
MAX_SUBPIXELS = 1 << 28  # width*height, times 9 with -filter
MAX_BOUNCES = 64
MAX_SAMPLES = 4096


class LimitError(ValueError):
    """A render request over one of the limits above."""


def check_render_limits(opts) -> None:
    if not (1 <= opts.width <= MAX_SIDE and 1 <= opts.height <= MAX_SIDE):
        raise LimitError(f"image size {opts.width}x{opts.height} is outside 1..{MAX_SIDE} "
                         "per side")
    sub = opts.width * opts.height * (9 if opts.filter else 1)
    if sub > MAX_SUBPIXELS:
        raise LimitError(f"image size {opts.width}x{opts.height} needs {sub} samples per pass, "
                         f"over the limit of {MAX_SUBPIXELS}")
    if not 0 <= opts.bounces <= MAX_BOUNCES:
        raise LimitError(f"bounces {opts.bounces} is outside 0..{MAX_BOUNCES}")
    if not 1 <= opts.samples <= MAX_SAMPLES:
        raise LimitError(f"samples {opts.samples} is outside 1..{MAX_SAMPLES}")
    if opts.backend not in ("llvm", "cuda"):
        raise LimitError(f"unknown backend '{opts.backend}' (expected llvm or cuda)")
    if opts.precision not in ("single", "double"):
        raise LimitError(f"unknown precision '{opts.precision}' (expected single or double)")
