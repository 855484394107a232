"""Scene values that kernels read at run time instead of holding as literals: the camera frame,
light colors, point lights' positions and falloffs, the background color and the ambient
light (materials were arrays already).

A literal is part of the kernel's code, so a scene whose light changed or whose camera moved
needed kernels of its own: 0.6-1.2 s of compiling (arch at 800x800 `-bounces 4 -shadows`: the
process took 1.3-1.9 s instead of 0.65 s). Read from memory, these values leave the kernels and
their cache entries the same. What stays literal, where the kernel gains from knowing it:
geometry (spheres, planes, transforms: unrolled, one test per object) and directional lights'
directions (their shadow rays all share that direction; read at run time it made warm renders
of the course scenes 2-5% slower, in three alternating runs). A value-dependent code path (a
subnormal falloff) still picks its own code.

Each value is a size-1 evaluated array, a kernel parameter. Arithmetic on it is the same IEEE
operation as on the literal, but for what Dr.Jit does with literals: it turns a division by
one into a multiplication by its reciprocal (a division by a run-time value stays one), and
it drops a multiplication by a literal 1 or an addition of a literal 0, where the run-time
operation flushes a subnormal operand to 0 on its worker threads (FTZ/DAZ). The only value
where that reached an image was the ambient light of 1 forced on a scene without lights,
which stays literal (shading.Shader); elsewhere a flushed term is added to others at run time
and flushed there as before. No byte can change: every value below 2^-126 quantises to 0.
"""
from __future__ import annotations

from typing import Any, Sequence

from .backend import import_drjit
from .vecmath import Types


def uniform(types: Types, value: float | Sequence[float]) -> Any:
    """value (a float or a 3-vector) as a run-time Float or Array3f of width 1."""
    dr = import_drjit()
    if isinstance(value, (int, float)):
        return dr.opaque(types.Float, float(value))
    return dr.opaque(types.Array3f, [float(c) for c in value])
