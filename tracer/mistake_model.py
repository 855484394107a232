"""What a mistake is, as a value: its family, what a scene and request must have for it to
show, its parameter and its entry (tracer/mistakes.py holds the catalogue of hand-written
entries, tracer/operators.py the entries generated at the sites of the course's formulas)."""
from __future__ import annotations

from dataclasses import dataclass
from enum import StrEnum

from .scene.request import KINDS


class Family(StrEnum):
    LIGHTS = "lights"
    SHADING = "shading"
    SHADOWS = "shadows"
    REFLECTION = "reflection"
    GEOMETRY = "geometry"
    CAMERA = "camera"


class Needs(StrEnum):
    """What a scene and request must have for a mistake to change an image."""

    POINT_LIGHT = "a point light"
    DIRECTIONAL_LIGHT = "a directional light"
    LIGHT = "a light"
    SHADOWS = "-shadows"
    BOUNCES = "-bounces"
    FILTER = "-filter"
    JITTER = "-jitter"
    SPECULAR = "a material with a non-zero ks"
    SPHERE = "a sphere"
    PLANE = "a plane"
    TRIANGLE = "a triangle"
    TRANSFORM = "a transformed object"


@dataclass(frozen=True)
class Parameter:
    """A mistake's number: what it is, the course's own value (the mistake with it is no
    mistake), the values a search tries first and the range it may refine within."""

    name: str
    course: float | None
    sweep: tuple[float, ...]
    low: float
    high: float
    integer: bool = False  # a count (bounces): refined in steps of 1
    geometric: bool = False  # an offset: refined on a log scale
    # a choice, not a quantity: value k means names[k] (a weight replaced by another term)
    names: tuple[str, ...] = ()

    def spell(self, value: float) -> str:
        return self.names[int(value)] if self.names else f"{value:g}"


@dataclass(frozen=True)
class Mistake:
    code: str  # a catalogue entry's Code, or a generated one's site.operator
    family: Family
    function: str  # where it lives in the starter code
    does: str  # what the program does, completing "your program ..."
    needs: frozenset[Needs]
    kinds: frozenset[str]  # the image kinds it can change
    parameter: Parameter | None = None
    generated: bool = False  # made by an operator at a site (operators.py), not hand-written

    def describe(self, value: float | None = None) -> str:
        """What the program does, with the parameter's value where it has one."""
        if self.parameter is None or value is None:
            return self.does
        return self.does.format(value=self.parameter.spell(value))


COLOR = frozenset({"color"})
HITS = frozenset(KINDS)  # where what is hit changes
NORMALS = frozenset({"color", "normals"})
OFFSET = Parameter("offset", 0.01, (0.0, 1e-4, 1e-3, 0.05, 0.1, 0.2), 0.0, 1.0,
                   geometric=True)
