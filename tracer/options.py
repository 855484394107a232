"""The tracer's own render settings beside the course request, as closed sets validated in one
place: a RenderOptions holds members of these enums whatever spelling it was given ("robust"
and Mode.ROBUST alike, as the command line, the harness and tests spell them)."""
from __future__ import annotations

from dataclasses import dataclass
from enum import StrEnum
from typing import TypeVar

from .scene.errors import quote
from .scene.request import RenderRequest


class Mode(StrEnum):
    COURSE = "course"  # the course program's arithmetic, quirks included, bit for bit
    ROBUST = "robust"  # scale-aware ray offsets, stable roots, watertight triangles (robust.py)


class Precision(StrEnum):
    SINGLE = "single"  # float32, as the course computes
    DOUBLE = "double"  # float64 (the stress studies' reference)


class Accel(StrEnum):
    BVH = "bvh"
    BRUTE = "brute"  # every ray tests every triangle (for checking the BVH)


class Backend(StrEnum):
    LLVM = "llvm"  # CPU
    CUDA = "cuda"  # NVIDIA GPU


class OptionError(ValueError):
    """An unknown value of a tracer setting; the message names the setting and the choices."""


E = TypeVar("E", bound=StrEnum)


def choice(kind: type[E], name: str, value: str) -> E:
    """`value` as a member of `kind`, else OptionError naming the setting."""
    try:
        return kind(value)
    except ValueError:
        raise OptionError(f"unknown {name} {quote(str(value))} (expected "
                          f"{' or '.join(kind)})") from None


@dataclass(frozen=True)
class RenderOptions(RenderRequest):
    """A render request with the tracer's own settings."""

    backend: Backend = Backend.LLVM
    precision: Precision = Precision.SINGLE
    accel: Accel = Accel.BVH
    mode: Mode = Mode.COURSE
    # auxiliary images (auxiliary.py) to render beside the kinds, from the same rays
    aux: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        super().__post_init__()
        for name, kind in (("backend", Backend), ("precision", Precision), ("accel", Accel),
                           ("mode", Mode)):
            object.__setattr__(self, name, choice(kind, name, getattr(self, name)))
