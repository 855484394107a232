"""Limits checked before any work starts, so hostile input fails fast with a clear message."""
from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

from .errors import SceneError
from .model import reflective_mask

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
# Every sphere and plane test is unrolled into the kernel: once for the camera rays, once more
# in the mirror loop (-bounces on a reflective scene), and once per light for the shadow rays
# of each. LLVM's compile time grows about with the square of that count (measured on one busy
# core: 500 tests ~3 s, 1000 ~13 s, 2000 ~35-70 s, 4000 several minutes), so a kernel holds at
# most this many (--max-kernel-tests raises it, for scenes worth a long compile).
DEFAULT_MAX_KERNEL_TESTS = 1024
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


# Memory and work of one render, estimated from the request and the scene before any work
# starts, the same for both renderers and every command (--max-memory, --max-rays raise them).
DEFAULT_MAX_MEMORY = 8 << 30  # bytes: a third of a 24 GiB machine, with room for the rest
DEFAULT_MAX_RAYS = 1 << 36  # ray casts per render: at ~10-30 M rays/s, one to two hours
# What a render holds per (sub)pixel and channel: the device buffer, its host copy, two
# temporaries (division by the sample count, the filter, the 8-bit quantisation) and the
# encoder's rows: 5 float32s (measured: 14.7 bytes at 1024x1024, every kind,
# tests/tracer/test_budget).
BYTES_PER_CHANNEL = 5 * 4
CHANNELS = {"color": 3, "normals": 3, "depth": 1}
# A mesh face costs, from reading it in Python (a tuple in a list: ~210 bytes measured at
# peak) to the BVH, triangle records and their device copies: ~720 bytes (measured: 12 GB for
# 2^24 faces end to end). Counted from the file's 'f' lines before it is parsed.
PARSE_BYTES_PER_FACE = 720
PARSE_BYTES_PER_VERTEX = 150
# A decoded cube-map texel at its peak, the larger of the two renderers: the 8-bit decode, and
# in the tracer its packed and device copies and float64 RGB on the device (3 + 3 + 3 + 24), in
# the Mitsuba reference float32 RGB on the host, packed and on the device (3 + 3 * 12).
BYTES_PER_TEXEL = 3 + 3 * 12


class BudgetError(ValueError):
    """A render whose estimated memory or work is over the budget (one-line message)."""


@dataclass(frozen=True)
class Budget:
    memory_bytes: int = DEFAULT_MAX_MEMORY
    rays: int = DEFAULT_MAX_RAYS
    kernel_tests: int = DEFAULT_MAX_KERNEL_TESTS

    def check_memory(self, needed: int, what: str) -> None:
        if needed > self.memory_bytes:
            raise BudgetError(f"{what} needs about {gib(needed)} of memory, over the limit of "
                              f"{gib(self.memory_bytes)} (--max-memory raises it)")


def gib(n: int) -> str:
    return f"{n / (1 << 30):.2f} GiB" if n >= 1 << 28 else f"{n / (1 << 20):.1f} MiB"


_SIZE_RE = re.compile(r"([0-9]+(?:\.[0-9]*)?)\s*([KMGT]?)(?:I?B)?", re.IGNORECASE)


def parse_bytes(text: str) -> int:
    """'8G', '512M', '1.5GiB' or a plain number of bytes; ValueError otherwise."""
    m = _SIZE_RE.fullmatch(text.strip())
    value = float(m.group(1)) * (1 << (10 * "KMGT".find(m.group(2).upper()) + 10)) \
        if m and m.group(2) else float(m.group(1)) if m else -1.0
    if not 0 < value < 2.0**60:
        raise ValueError(f"expected a positive size such as 8G or 512M, found {text!r}")
    return int(value)


def render_estimate(request, lights: int, shadow_lights: int | None = None) -> tuple[int, int]:
    """(bytes, rays) of a render's images and ray casts: every (sub)pixel and jitter sample
    casts a primary ray, and per mirror level a reflected ray, each with one shadow ray per
    light under -shadows (an upper bound: misses and non-mirrors stop early)."""
    sub = request.width * request.height * (9 if request.filter else 1)
    channels = sum(CHANNELS[k] for k in request.kinds)
    samples = request.samples if request.jitter else 1
    per_hit = 1 + (lights if request.shadows else 0)
    rays = sub * samples * (1 + request.bounces) * per_hit
    return sub * channels * BYTES_PER_CHANNEL, rays


def count_spheres_planes(obj) -> int:
    from .model import Plane, Sphere, primitives

    return sum(isinstance(o, (Sphere, Plane)) for o, _ in primitives(obj))


def _compile_time(tests: int) -> str:
    seconds = 13 * (tests / 1000) ** 2  # the measured growth (DEFAULT_MAX_KERNEL_TESTS)
    return f"about {seconds:.0f} s" if seconds < 3600 else "hours"


def scene_request_problem(scene, request, budget: Budget = Budget()) -> str | None:
    """What puts a render of this scene over a limit, or None: the shadow tests compiled into
    the kernel, the images' memory and the rays cast. The same for both renderers; each raises
    its own error with the message."""
    shapes = count_spheres_planes(scene.root)
    mirrors = request.bounces > 0 and bool(reflective_mask(scene.materials).any())
    shadow_rays = len(scene.lights) if request.shadows else 0
    tests = shapes * (1 + mirrors) * (1 + shadow_rays)
    if tests > budget.kernel_tests:
        return (f"{shapes} spheres and planes" + (" with mirrors" if mirrors else "")
                + (f" and -shadows from {shadow_rays} lights" if shadow_rays else "")
                + f" make {tests} sphere and plane tests in the kernel, over the limit of "
                f"{budget.kernel_tests} (--max-kernel-tests raises it; compiling would take "
                f"{_compile_time(tests)})")
    image_bytes, rays = render_estimate(request, len(scene.lights))
    try:
        budget.check_memory(image_bytes, f"a {request.width}x{request.height} render of "
                                         f"{', '.join(request.kinds)}")
    except BudgetError as e:
        return str(e)
    if rays > budget.rays:
        return (f"the render casts up to {rays:.3g} rays, over the limit of "
                f"{budget.rays:.3g} (--max-rays raises it)")
    return None
