"""The course program's quirks: behaviours of that one program, reproduced byte for byte by
course mode, that no handout of the assignment asks for (docs/course-format.md marks each rule
`required`, `convention` or `quirk`).

A quirk here has a plain reading: what a program that follows the handouts does instead,
rendered by switching on one of the catalogue's mistakes (mistakes.py). The harness renders a
case's "required-only" reference (the course's, with the plain reading of every quirk the
case can show) and gives a candidate that matches it `pass (quirk)` rather than `fail`
(harness/diagnosis/quirks.py); `--strict` keeps the byte-for-byte verdict.

The spec's other quirks have no single plain reading, or show only on scenes a check does not
run by default: the plane's normal kept as written (a program may normalise it in the
constructor or only for shading), the 0.01 offset of shadow and reflection rays (the handouts
ask for "some E"; the catalogue searches the value), the ambient light forced to white in a
scene without lights, the sphere hit at t = 10000 by a NaN ray and the x86 conversion of an
overflowing color (extreme scenes). They are judged byte for byte.
"""
from __future__ import annotations

from dataclasses import dataclass

from .mistakes import Switch


@dataclass(frozen=True)
class Quirk:
    code: str
    rule: str  # the spec's section
    function: str  # where a student's program decides it
    course: str  # what the course program does
    plain: str  # what a program that follows the handouts does
    switch: Switch  # the plain reading, as a mistake of the catalogue

    def describe(self) -> str:
        return (f"{self.function}: the course program {self.course}; your program "
                f"{self.plain}. The handouts do not ask for this")


QUIRKS: tuple[Quirk, ...] = (
    Quirk("mirror_gate", "§6 Shading", "Renderer::traceRay",
          "only mirrors a material whose specular color has a Euclidean length above 0.1",
          "mirrors every material, weighted by its specular color",
          Switch("reflection_gate", 0.0)),
)
BY_CODE = {q.code: q for q in QUIRKS}
BY_SWITCH = {q.switch: q for q in QUIRKS}
