"""The tracer's own render settings beside the course request, as closed sets validated in one
place: a RenderOptions holds members of these enums whatever spelling it was given ("robust"
and Mode.ROBUST alike, as the command line, the harness and tests spell them)."""
from __future__ import annotations

from dataclasses import dataclass
from enum import StrEnum
from typing import TypeVar

from .mistakes import MISTAKES, Code, MistakeError, Switch, hooks, switches
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
# the mistakes that are the request changed (RenderOptions.__post_init__)
HOOKS = hooks(
    __name__,
    Code.FILTER_IGNORED,
    Code.JITTER_SAMPLES,
)


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
    # mistakes switched on (mistakes.py), or their spellings ("shadow_offset=0.1")
    mistakes: tuple[Switch, ...] = ()
    # mistakes compiled into the kernel besides those on, off (arithmetic/mistaken.py): renders
    # with the same set share one kernel whichever are on
    mistake_kernel: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        super().__post_init__()
        for name, kind in (("backend", Backend), ("precision", Precision), ("accel", Accel),
                           ("mode", Mode)):
            object.__setattr__(self, name, choice(kind, name, getattr(self, name)))
        try:
            object.__setattr__(self, "mistakes", switches(self.mistakes))
        except MistakeError as e:
            raise OptionError(str(e)) from None
        unknown = sorted(set(self.mistake_kernel) - set(MISTAKES))
        if unknown:
            raise OptionError(f"unknown mistake {unknown[0]!r}")
        object.__setattr__(self, "mistake_kernel", tuple(sorted(set(self.mistake_kernel))))
        for s in self.mistakes:  # the mistakes that are the request changed
            if s.code == Code.FILTER_IGNORED:
                object.__setattr__(self, "filter", False)
            elif s.code == Code.JITTER_SAMPLES and s.value is not None:
                object.__setattr__(self, "samples", int(s.value))
        if (self.mistakes or self.mistake_kernel) and (self.mode != Mode.COURSE or self.aux):
            raise OptionError("mistakes are switches of course mode, without auxiliary "
                              "images")
