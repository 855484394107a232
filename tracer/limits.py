"""Render limits, checked before any work starts."""
from __future__ import annotations

from .scene.errors import quote

# With -shadows every light's shadow ray tests every sphere and plane, unrolled in the kernel:
# compile time grows faster than linearly in lights x (spheres + planes) (one CPU core: 2000
# ~15 s, 9000 ~200 s). The parser limits each count alone (scene.limits).
MAX_SHADOW_TESTS = 2048


class LimitError(ValueError):
    """A render request over one of the limits above."""


def check_render_limits(opts) -> None:
    problem = opts.limit_problem()
    if problem:
        raise LimitError(problem)
    if opts.backend not in ("llvm", "cuda"):
        raise LimitError(f"unknown backend {quote(str(opts.backend))} (expected llvm or cuda)")
    if opts.precision not in ("single", "double"):
        raise LimitError(f"unknown precision {quote(str(opts.precision))} "
                         "(expected single or double)")


def count_spheres_planes(obj) -> int:
    from .scene.model import Group, Plane, Sphere, Transform

    stack, n = [obj], 0
    while stack:
        o = stack.pop()
        if isinstance(o, Group):
            stack.extend(o.objects)
        elif isinstance(o, Transform):
            stack.append(o.child)
        elif isinstance(o, (Sphere, Plane)):
            n += 1
    return n


def check_scene_limits(scene, opts) -> None:
    """Limits that depend on the scene and the options together (after parsing, before the
    kernel is built)."""
    if opts.shadows and scene.lights:
        tests = len(scene.lights) * count_spheres_planes(scene.root)
        if tests > MAX_SHADOW_TESTS:
            raise LimitError(
                f"-shadows with {len(scene.lights)} lights and "
                f"{tests // len(scene.lights)} spheres and planes needs {tests} unrolled shadow "
                f"tests, over the limit of {MAX_SHADOW_TESTS}")
