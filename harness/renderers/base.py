"""The Renderer protocol: anything that renders a course scene for a RenderRequest.

    session = renderer.open(scene_path, request)   # scene loaded, kernels may be traced
    try:
        images = session.render()                  # may be called again (warm re-runs)
    finally:
        session.close()

The harness speaks only of roles (candidate, reference) and shows `renderer.name`. What a
renderer can do is in its Capabilities; what goes wrong while it renders is a RenderError with
a finding code, never an exception of another type.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from enum import StrEnum
from pathlib import Path
from typing import Protocol, runtime_checkable

import numpy as np

from raycheck.tracer.scene.request import KINDS, RenderRequest


@dataclass(frozen=True)
class Capabilities:
    float_images: bool  # images are the float values as rendered; else the 8-bit PNG bytes
    seedable: bool      # honours request.seed and request.samples (-jitter streams we choose)
    warm_reruns: bool   # a second render() of a session is cheaper than the first
    reseed: bool = False  # a session renders another seed (session.reseed) without reloading
    kinds: tuple[str, ...] = KINDS


class RenderError(Exception):
    """A render that failed as a whole (timeout, crash, exit status, bad input): `code` is the
    finding code that check.json and the pages carry; `log` the renderer's last output lines;
    `written` the kinds whose image files it wrote before it failed."""

    def __init__(self, code: str, message: str, log: str = "",
                 written: tuple[str, ...] = ()) -> None:
        super().__init__(message)
        self.code = code
        self.message = message
        self.log = log
        self.written = written


@dataclass(frozen=True)
class KindError:
    """One image of a render that could not be read (the others may be fine)."""

    code: str  # missing_output, bad_png, wrong_size
    message: str


@dataclass
class Images:
    """What one render() produced. Float images are (h, w, 3) or (h, w) for depth, row 0 at
    the top; 8-bit ones are (h, w, 3) uint8 as the PNG holds them."""

    images: dict[str, np.ndarray]
    seconds: float
    errors: dict[str, KindError] = field(default_factory=dict)  # kind -> why it is missing
    log: str = ""  # the renderer's last output lines, if it has any


def fits_request(images: dict, request: RenderRequest) -> bool:
    """Whether images hold every kind the request asks for, at its size, as Images holds them:
    a cache entry read back that does not (damaged, or edited by hand) is rendered again."""
    size = (request.height, request.width)
    for kind in request.kinds:
        image = images.get(kind)
        if not isinstance(image, np.ndarray):
            return False
        floats = size + (() if kind == "depth" else (3,))
        if not ((image.dtype.kind == "f" and image.shape == floats)
                or (image.dtype == np.uint8 and image.shape == size + (3,))):
            return False
    return True


class Session(Protocol):
    def render(self) -> Images: ...

    def close(self) -> None: ...


@runtime_checkable
class Reseedable(Protocol):
    """A session that can draw its next render's jitter from another seed without opening
    again: the sessions of every renderer whose caps.reseed is true."""

    def reseed(self, seed: int) -> None: ...


class Debugger(StrEnum):
    """A debugger a failed program runs again under, and what it asks (TOOLS: the command)."""

    GDB = "gdb"  # where it stopped: the signal and the stack
    MEMCHECK = "valgrind"  # valgrind's memcheck: every invalid read and write where made
    HANG = "hang"  # gdb, stopping a program that runs on: the function that does not return


TOOLS = {Debugger.GDB: "gdb", Debugger.MEMCHECK: "valgrind", Debugger.HANG: "gdb"}


@runtime_checkable
class Debuggable(Protocol):
    """A renderer that can run a request again under a debugger, for where it crashed: the
    native programs CommandRenderer runs."""

    def debug(self, scene: Path, request: RenderRequest, debugger: Debugger) -> str | None: ...


class Renderer(Protocol):
    @property
    def name(self) -> str:  # shown in pages: "tracer", "mitsuba", "student a2"
        ...

    @property
    def caps(self) -> Capabilities: ...

    def identity(self) -> dict:
        """What makes this renderer's results reproducible: a version or a file hash."""
        ...

    def open(self, scene: Path, request: RenderRequest) -> Session: ...
