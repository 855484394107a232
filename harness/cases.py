"""The case matrix: for each scene, the feature cases that can change its images.

A case is a scene with one feature set (plain, -shadows, -bounces N, both, -jitter, -filter,
both) and the image kinds that feature can change. Cases a scene cannot exercise are returned
as skips with the reason, which the report lists.
"""
from __future__ import annotations

from dataclasses import dataclass

from raycheck.tracer.analysis import SceneInfo, analyze
from raycheck.tracer.scene import load_scene
from raycheck.tracer.scene.request import KINDS, RenderRequest

from .catalog import BundledScene

DEFAULT_BOUNCES = 4
DEFAULT_CASE_SIZE = (128, 128)


@dataclass(frozen=True)
class Case:
    scene: BundledScene
    feature: str  # plain, shadows, bounces4, shadows+bounces4, jitter, filter, jitter+filter
    request: RenderRequest  # the render, with the image kinds this feature can change

    @property
    def id(self) -> str:
        return f"{self.scene.name}/{self.feature}"

    @property
    def jittered(self) -> bool:
        return self.request.jitter


@dataclass(frozen=True)
class Skip:
    scene: BundledScene
    feature: str
    reason: str

    @property
    def id(self) -> str:
        return f"{self.scene.name}/{self.feature}"


def case_matrix(scene: BundledScene, size: tuple[int, int] | None = None,
                info: SceneInfo | None = None) -> tuple[list[Case], list[Skip]]:
    """The scene's cases at `size` (default: the size its header asks for, else
    DEFAULT_CASE_SIZE) and the features it cannot exercise, with the reason."""
    info = info or analyze(load_scene(scene.path))
    typical = scene.typical_request(size or scene.size or DEFAULT_CASE_SIZE)
    n = typical.bounces or DEFAULT_BOUNCES
    base = typical.with_features()
    # (feature, request, flags that must matter for the case to exist)
    candidates = [
        ("plain", base.with_kinds(KINDS), ()),
        ("shadows", base.with_features(shadows=True), ("-shadows",)),
        (f"bounces{n}", base.with_features(bounces=n), ("-bounces",)),
        (f"shadows+bounces{n}", base.with_features(shadows=True, bounces=n),
         ("-shadows", "-bounces")),
        ("jitter", base.with_features(jitter=True).with_kinds(KINDS), ("-jitter",)),
        ("filter", base.with_features(filter=True).with_kinds(KINDS), ("-filter",)),
        ("jitter+filter", base.with_features(jitter=True, filter=True).with_kinds(KINDS),
         ("-jitter", "-filter")),
    ]
    cases, skips = [], []
    for feature, request, needs in candidates:
        idle = [f for f in needs if not info.matters(f)]
        if idle:
            reasons = "; ".join(f"{f} has {info.flag_effects[f]}" for f in idle)
            skips.append(Skip(scene, feature, reasons))
        else:
            cases.append(Case(scene, feature, request))
    return cases, skips


def feature_name(request: RenderRequest) -> str:
    """The case matrix's name for a request's features (plain, shadows+bounces4, ...)."""
    parts = (["shadows"] if request.shadows else []) + \
        ([f"bounces{request.bounces}"] if request.bounces else []) + \
        (["jitter"] if request.jitter else []) + (["filter"] if request.filter else [])
    return "+".join(parts) or "plain"


def kind_skip_reason(feature: str, kind: str) -> str:
    """Why a kind is not compared in a case (shadows and mirrors change only the color)."""
    return f"{feature} does not change the {kind} image (primary hits only)"
