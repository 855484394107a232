"""The renderers the harness can run: raycheck's tracer and the Mitsuba reference in process,
and any course program as a subprocess (see base.Renderer)."""
from __future__ import annotations

from raycheck.tracer.scene.limits import Budget

from .base import (
    Capabilities,
    Debuggable,
    Debugger,
    Images,
    KindError,
    Renderer,
    RenderError,
    Reseedable,
    Session,
    fits_request,
)
from .builtin import MitsubaRenderer, TracerRenderer, visible_depth_range
from .command import CommandRenderer, Limits

BUILTIN: dict[str, type[TracerRenderer] | type[MitsubaRenderer]] = {
    "tracer": TracerRenderer, "mitsuba": MitsubaRenderer}
ENGINE_PACKAGES = ("mitsuba", "drjit")  # the engines' versions, for the provenance


def renderer_from_spec(spec: str, limits: Limits | None = None,
                       budget: Budget = Budget()) -> Renderer:
    """`tracer` or `mitsuba` (in process, within the memory and ray budget), else a command
    line run as a course program (within its process limits)."""
    if spec in BUILTIN:
        return BUILTIN[spec](budget=budget)
    return CommandRenderer.from_string(spec, limits)


def stress_reference() -> Renderer:
    """What the stress page measures every variant against: the tracer, robust, in float64."""
    return TracerRenderer("tracer robust float64", {"mode": "robust", "precision": "double"})


def stress_variants() -> dict[str, Renderer]:
    """The variants the stress page compares on the extreme scenes."""
    return {
        "course": TracerRenderer("tracer course", {"mode": "course", "precision": "single"}),
        "robust": TracerRenderer("tracer robust", {"mode": "robust", "precision": "single"}),
        "course-float64": TracerRenderer("tracer course float64",
                                         {"mode": "course", "precision": "double"}),
        "mitsuba": MitsubaRenderer(),
    }


__all__ = ["BUILTIN", "ENGINE_PACKAGES", "Capabilities", "CommandRenderer", "Debuggable",
           "Debugger", "Images", "KindError", "Limits", "MitsubaRenderer", "RenderError",
           "Renderer", "Reseedable", "Session", "TracerRenderer", "fits_request",
           "renderer_from_spec", "stress_reference", "stress_variants", "visible_depth_range"]
