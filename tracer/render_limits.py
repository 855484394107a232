"""Render limits, checked before any work starts."""
from __future__ import annotations

from .scene.limits import Budget, scene_request_problem


class LimitError(ValueError):
    """A render request over a limit (scene.limits has them all, with their reasons)."""


def check_render_limits(opts) -> None:
    problem = opts.limit_problem()
    if problem:
        raise LimitError(problem)


def check_scene_limits(scene, opts, budget: Budget = Budget()) -> None:
    """Limits that depend on the scene and the options together (after parsing, before the
    kernel is built): see scene.limits.scene_request_problem."""
    problem = scene_request_problem(scene, opts, budget)
    if problem:
        raise LimitError(problem)
