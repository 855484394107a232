"""What to render, as the course command line asks for it: one type (RenderRequest); the command
line itself is parsed in flags.py (CourseCommand: the request, the scene, the files).

    request = request_from_argv(["-size", "40", "30", "-shadows", "-output", "a.png"])
    request                   # RenderRequest(width=40, height=30, shadows=True, kinds=("color",))
    request.to_argv("s.txt", {"color": "a.png"})   # the same course flags back

Both renderers' option records extend RenderRequest with their engine's own settings, the
harness's cases hold one, and external course programs get `to_argv()` of it: one way to spell
a render.
"""
from __future__ import annotations

from dataclasses import dataclass, fields, replace
from pathlib import Path
from typing import Mapping

from .limits import request_problem

KINDS = ("color", "normals", "depth")  # the image kinds, in the course's flag order
JITTER_SAMPLES = 16  # spec §9
DEFAULT_SEED = 0
OUTPUT_FLAGS = {"color": "-output", "normals": "-normals", "depth": "-depth"}


@dataclass(frozen=True)
class RenderRequest:
    """One render as the course command line asks for it (spec §10), plus the two jitter
    settings of ours (--samples, --seed) that a course program does not take."""

    width: int = 100
    height: int = 100
    bounces: int = 0
    shadows: bool = False
    jitter: bool = False
    filter: bool = False
    kinds: tuple[str, ...] = ("color",)  # images wanted, in KINDS order
    depth_min: float = 0.0
    depth_max: float = 1.0
    samples: int = JITTER_SAMPLES  # jittered samples per (sub)pixel with -jitter
    seed: int = DEFAULT_SEED  # of the -jitter samples

    def __post_init__(self) -> None:
        unknown = [k for k in self.kinds if k not in KINDS]
        if unknown:
            raise ValueError(f"unknown image kinds {unknown} (expected some of {KINDS})")
        # canonical order, no repeats: equal requests compare and hash equal
        object.__setattr__(self, "kinds", tuple(k for k in KINDS if k in self.kinds))

    def limit_problem(self) -> str | None:
        """What puts this request over a render limit (limits.py), or None."""
        return request_problem(self.width, self.height, self.filter, self.bounces, self.samples)

    def wants(self, kind: str) -> bool:
        return kind in self.kinds

    @property
    def size(self) -> tuple[int, int]:
        return self.width, self.height

    @property
    def depth_range(self) -> tuple[float, float]:
        return self.depth_min, self.depth_max

    @property
    def feature_flags(self) -> list[str]:
        """The flags that change what is traced: -bounces N, -shadows, -jitter, -filter."""
        out = ["-bounces", str(self.bounces)] if self.bounces else []
        return out + [f for f, on in (("-shadows", self.shadows), ("-jitter", self.jitter),
                                      ("-filter", self.filter)) if on]

    def with_features(self, bounces: int = 0, shadows: bool = False, jitter: bool = False,
                      filter: bool = False) -> RenderRequest:
        """The same request with exactly these features (size, kinds, depth range kept)."""
        return replace(self, bounces=bounces, shadows=shadows, jitter=jitter, filter=filter)

    def with_kinds(self, kinds: tuple[str, ...]) -> RenderRequest:
        return replace(self, kinds=tuple(kinds))

    def to_argv(self, input: str | Path, outputs: Mapping[str, str | Path] | None = None,
                ours: bool = False) -> list[str]:
        """The course command line for this request: -input, -size, the feature flags and one
        output flag per wanted kind (outputs: kind -> file name; default out.png, normals.png,
        depth.png). ours=True adds --samples and --seed where they differ from the defaults
        (course programs do not take them)."""
        names = {"color": "out.png", "normals": "normals.png", "depth": "depth.png"}
        names.update({k: str(v) for k, v in (outputs or {}).items()})
        argv = ["-input", str(input), "-size", str(self.width), str(self.height),
                *self.feature_flags]
        for kind in self.kinds:
            if kind == "depth":
                argv += ["-depth", f"{self.depth_min:g}", f"{self.depth_max:g}", names[kind]]
            else:
                argv += [OUTPUT_FLAGS[kind], names[kind]]
        if ours and self.jitter and self.samples != JITTER_SAMPLES:
            argv += ["--samples", str(self.samples)]
        if ours and self.jitter and self.seed != DEFAULT_SEED:
            argv += ["--seed", str(self.seed)]
        return argv


def request_fields(request: RenderRequest) -> dict:
    """The RenderRequest fields of a request or of an option record extending it, for building
    another record from it: RenderOptions(**request_fields(req), mode="robust")."""
    return {f.name: getattr(request, f.name) for f in fields(RenderRequest)}
