"""A course renderer with one known defect: `corrupt.py DEFECT <course flags>` renders the
flags with the reference tracer (raycheck.tracer, in this process), then breaks its output.
`Corrupted(DEFECT)` is the same renderer in process (the findings benchmark and tests).

Defects of the render request: none (the tracer as it is), no_shadows (drops -shadows),
no_bounces (drops -bounces), one_bounce_fewer (-bounces N-1), no_filter, no_jitter (one sample
per pixel), samples4 (4 jittered samples instead of 16), double_size (renders 2W x 2H),
no_normals (writes no normals file), always_shadows (-shadows whether asked or not),
always_bounces (-bounces 4 where not asked); shared_pattern (one jitter pattern for every pixel:
tools/jitter_defects.py).
Defects of the images: filter_2x (the color image of a -filter render twice as bright, clipped
at 255), flip (every image upside down), flip_h (left-right), transpose, swap_rb (every image as
BGR), gamma (color gamma-encoded, 1/2.2), offset (color +12 levels), filter_offset (color +12
levels with -filter), rounding (every value rounded instead of truncated), normals_clip (normals
n*255, clipped), normals_abs (|n|*255), depth_inverted (255 - depth), first_row (every image
black but its bottom row: a pixel loop left after its first row), first_column (black but its
first column), depth_unclamped (depth bytes wrapped as C's (unsigned char)(int)(255*v)), acne
(with -shadows, every other lit pixel of a surface at half its value), few_shadows (with
-shadows, shadows only on every fourth row).
Defects of the shading, the tracer patched while it renders (patched.py): specular_gated,
ambient_per_light, half_vector, no_offset.
Defects of the geometry, the tracer patched too (geometry_bugs.py): unnormalised_normals,
one_material, pixel_centre, half_shift, sphere_shrunk.
A defect may carry mistakes of the catalogue, DEFECT@MISTAKES (depth_inverted@falloff_power=1):
the tracer renders with them on, then the defect breaks its output.
Defects of the process: exit3 (renders, then exits with status 3), sleep (sleeps a minute,
writes nothing), truncate (the color PNG cut to half its bytes), segv (SIGSEGV before writing),
segv_filter (SIGSEGV with -filter; without it, the tracer's images), segv_transformed (SIGSEGV
where the scene holds a transformed object: a Transform::intersect reporting a hit it did not
record, whose null material shade reads), no_output (exits with status 0 without writing an
image).
"""
from __future__ import annotations

import os
import signal
import sys
import time
from contextlib import nullcontext
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Callable

if __name__ == "__main__":  # a renderer process, set up as `python -m raycheck.tracer` is
    from raycheck.tracer.kernel.backend import begin_render_process, end_render_process

    begin_render_process()  # before numpy's import

import numpy as np  # noqa: E402

# --- geometry defects (geometry_bugs.py): patched like PATCHED's, while the tracer renders
from geometry_bugs import GEOMETRY  # noqa: E402
from patched import PATCHED  # noqa: E402

PATCHES = {**PATCHED, **GEOMETRY}
# ---

REQUEST_DEFECTS: dict[str, Callable] = {
    "none": lambda r: r,
    "no_shadows": lambda r: replace(r, shadows=False),
    "no_bounces": lambda r: replace(r, bounces=0),
    "one_bounce_fewer": lambda r: replace(r, bounces=max(r.bounces - 1, 0)),
    "no_filter": lambda r: replace(r, filter=False),
    "no_jitter": lambda r: replace(r, jitter=False),
    "samples4": lambda r: replace(r, samples=4) if r.jitter else r,
    "double_size": lambda r: replace(r, width=2 * r.width, height=2 * r.height),
    "no_normals": lambda r: r,
    "always_shadows": lambda r: replace(r, shadows=True),
    "always_bounces": lambda r: r if r.bounces else replace(r, bounces=4),
}
GAMMA = 2.2
OFFSET_LEVELS = 12


def shown(values: np.ndarray) -> np.ndarray:
    """Float values as the course shows them (NaN, inf, huge: 0), clipped to [0, 1]."""
    with np.errstate(invalid="ignore"):
        ok = np.abs(values) < 1e30
    return np.clip(np.where(ok, values, 0.0), 0.0, 1.0).astype(np.float64)


def rgb(q: np.ndarray) -> np.ndarray:
    return np.repeat(q[..., None], 3, axis=2) if q.ndim == 2 else q


def course_bytes(values: np.ndarray) -> np.ndarray:
    from raycheck.tracer.image import to_rgb8

    return to_rgb8(values).astype(np.int32)


def by_kind(kinds: tuple[str, ...], change: Callable) -> Callable:
    """An image defect of the course bytes, applied to the given kinds only."""
    return lambda kind, values, request, again: \
        change(course_bytes(values)) if kind in kinds else course_bytes(values)


def filter_2x(kind, values, request, again):
    b = course_bytes(values)
    return np.minimum(b * 2, 255) if kind == "color" and request.filter else b


def gamma(kind, values, request, again):
    if kind != "color":
        return course_bytes(values)
    return rgb(np.floor(255.0 * shown(values) ** (1 / GAMMA))).astype(np.int32)


def rounding(kind, values, request, again):
    return rgb(np.floor(shown(values) * np.float32(255.0) + 0.5)).astype(np.int32)


def normals(mapping: Callable) -> Callable:
    def change(kind, values, request, again):
        if kind != "normals":
            return course_bytes(values)
        n = 2.0 * shown(values) - 1.0
        return np.clip(np.floor(mapping(n) * 255.0), 0, 255).astype(np.int32)
    return change


def unshadowed(request, again) -> tuple[np.ndarray, np.ndarray]:
    """The color bytes without -shadows, and where a primary ray hits a surface."""
    plain = again(replace(request, shadows=False, kinds=("color", "depth")))
    with np.errstate(invalid="ignore"):
        hit = np.abs(plain["depth"]) < 1e30
    return course_bytes(plain["color"]), hit


def acne(kind, values, request, again):
    b = course_bytes(values)
    if kind != "color" or not request.shadows:
        return b
    plain, hit = unshadowed(request, again)
    rows, cols = np.indices(b.shape[:2])
    speckle = hit & ((rows + cols) % 2 == 0) & (np.abs(b - plain).max(axis=2) <= 1)
    return np.where(speckle[..., None], b // 2, b)


def few_shadows(kind, values, request, again):
    b = course_bytes(values)
    if kind != "color" or not request.shadows:
        return b
    plain, _ = unshadowed(request, again)
    keep = np.arange(b.shape[0])[:, None, None] % 4 == 0
    return np.where(keep, b, plain)


IMAGE_DEFECTS: dict[str, Callable] = {
    "filter_2x": filter_2x,
    "flip": by_kind(("color", "normals", "depth"), lambda b: b[::-1]),
    "flip_h": by_kind(("color", "normals", "depth"), lambda b: b[:, ::-1]),
    "transpose": by_kind(("color", "normals", "depth"), lambda b: b.transpose(1, 0, 2)),
    "swap_rb": by_kind(("color", "normals", "depth"), lambda b: b[..., ::-1]),
    "gamma": gamma,
    "offset": by_kind(("color",), lambda b: np.clip(b + OFFSET_LEVELS, 0, 255)),
    "filter_offset": lambda kind, values, request, again: np.clip(
        course_bytes(values) + OFFSET_LEVELS * (kind == "color" and request.filter), 0, 255),
    "rounding": rounding,
    "normals_clip": normals(lambda n: n),
    "normals_abs": normals(np.abs),
    "depth_inverted": by_kind(("depth",), lambda b: 255 - b),
    # pixels never written (black): a pixel loop left after its first row, or first column
    "first_row": by_kind(("color", "normals", "depth"),
                         lambda b: np.where(np.arange(len(b))[:, None, None] == len(b) - 1, b, 0)),
    "first_column": by_kind(("color", "normals", "depth"),
                            lambda b: np.where(np.arange(b.shape[1])[:, None] == 0, b, 0)),
    "acne": acne,
    "few_shadows": few_shadows,
}


# --- depth_unclamped: the depth floats written without the course's clamp to [0, 1]
def depth_unclamped(kind, values, request, again):
    if kind != "depth":
        return course_bytes(values)
    with np.errstate(all="ignore"):  # x86's float -> int32 (NaN, inf, out of range: INT_MIN)
        b = (values.astype(np.float32) * np.float32(255.0)).astype(np.int32).astype(np.uint8)
    return rgb(b).astype(np.int32)


IMAGE_DEFECTS["depth_unclamped"] = depth_unclamped
# ---
PROCESS_DEFECTS = ("exit3", "sleep", "truncate", "segv", "segv_filter", "segv_transformed",
                   "no_output")
DEFECTS = tuple(REQUEST_DEFECTS) + tuple(IMAGE_DEFECTS) + tuple(PATCHES) + PROCESS_DEFECTS + \
    ("shared_pattern",)
REPO = Path(__file__).resolve().parents[2]


def shared_pattern(scene: Path, request) -> dict[str, np.ndarray]:
    """The -jitter request rendered with one jitter pattern for every pixel."""
    sys.path.insert(0, str(REPO / "tools"))
    from jitter_defects import shared

    return shared(scene, request)


def render_floats(scene: Path, request, mistakes: tuple[str, ...] = ()) -> dict[str, np.ndarray]:
    from raycheck.tracer.options import RenderOptions
    from raycheck.tracer.render import render
    from raycheck.tracer.scene import load_scene
    from raycheck.tracer.scene.request import request_fields

    result = render(load_scene(scene), RenderOptions(**request_fields(request),
                                                     mistakes=mistakes))
    return {k: getattr(result, k) for k in request.kinds}


def corrupted_images(defect: str, scene: Path, request) -> dict[str, np.ndarray]:
    """kind -> (h, w, 3) uint8: the tracer's images of the request with the defect (DEFECT, or
    DEFECT@MISTAKES: rendered with the catalogue's mistakes on, as --mistake spells them)."""
    defect, _, mistakes = defect.partition("@")
    rendered = REQUEST_DEFECTS.get(defect, REQUEST_DEFECTS["none"])(request)
    if defect == "shared_pattern" and request.jitter:
        floats = shared_pattern(scene, request)
    else:
        with PATCHES.get(defect, nullcontext)():
            floats = render_floats(scene, rendered,
                                   tuple(mistakes.split(",")) if mistakes else ())
    change = IMAGE_DEFECTS.get(defect, lambda kind, values, r, again: course_bytes(values))
    again = lambda r: render_floats(scene, r)  # noqa: E731 (a second render, if needed)
    images = {k: change(k, v, request, again).astype(np.uint8) for k, v in floats.items()}
    return {k: v for k, v in images.items() if not (defect == "no_normals" and k == "normals")}


@dataclass
class Corrupted:
    """The wrapper as an in-process Renderer (8-bit images, as a PNG-writing program gives)."""

    defect: str

    @property
    def name(self) -> str:
        return f"corrupt {self.defect}"

    @property
    def caps(self):
        from raycheck.harness.renderers.base import Capabilities

        return Capabilities(float_images=False, seedable=True, warm_reruns=False)

    def identity(self) -> dict:
        return {"name": self.name}

    def open(self, scene: Path, request):
        defect = self.defect

        class Session:
            def render(self):
                from raycheck.harness.renderers.base import Images

                start = time.perf_counter()
                images = corrupted_images(defect, scene, request)
                return Images(images, time.perf_counter() - start)

            def close(self) -> None:
                pass

        return Session()


def transformed(scene: Path) -> bool:
    from raycheck.tracer.scene import load_scene
    from raycheck.tracer.shade.auxiliary import scene_objects

    return any(o.transformed for o in scene_objects(load_scene(scene)))


def main(argv: list[str]) -> int:
    defect, flags = argv[0], argv[1:]
    if defect not in DEFECTS:
        print(f"corrupt.py: unknown defect {defect!r}", file=sys.stderr)
        return 2
    if defect == "sleep":
        time.sleep(60)
        return 0
    if defect == "no_output":
        return 0
    if defect == "segv" or defect == "segv_filter" and "-filter" in flags:
        os.kill(os.getpid(), signal.SIGSEGV)

    from PIL import Image

    from raycheck.tracer.cli import EXTRA_OPTIONS
    from raycheck.tracer.scene.flags import parse_course_flags

    cmd = parse_course_flags(flags, EXTRA_OPTIONS)
    if defect == "segv_transformed" and transformed(cmd.input):
        os.kill(os.getpid(), signal.SIGSEGV)
    images = corrupted_images(defect, cmd.input, cmd.request)
    for kind, path in cmd.outputs.items():
        if kind in images:
            Image.fromarray(images[kind], "RGB").save(path)
    if defect == "truncate":
        data = cmd.outputs["color"].read_bytes()
        cmd.outputs["color"].write_bytes(data[:len(data) // 2])
    return 3 if defect == "exit3" else 0


if __name__ == "__main__":
    end_render_process(main(sys.argv[1:]))
