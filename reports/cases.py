"""The case matrix: for each scene, the feature cases that can change its images.

A case is a scene with one feature set (plain, -shadows, -bounces N, both, -jitter, -filter,
both) and the image kinds that feature can change. Cases a scene cannot exercise are returned
as skips with the reason, which the report lists.
"""
from __future__ import annotations

from dataclasses import dataclass

from tracer.analysis import SceneInfo, analyze
from tracer.scene import load_scene

from .catalog import BundledScene

KINDS = ("color", "normals", "depth")
DEFAULT_BOUNCES = 4


@dataclass(frozen=True)
class Case:
    scene: BundledScene
    feature: str
    flags: tuple[str, ...]  # course flags of the case (no -input/-output/-size/-depth)
    kinds: tuple[str, ...]  # image kinds this feature can change

    @property
    def id(self) -> str:
        return f"{self.scene.name}/{self.feature}"

    @property
    def jittered(self) -> bool:
        return "-jitter" in self.flags

    @property
    def bounces(self) -> int:
        return int(self.flags[self.flags.index("-bounces") + 1]) if "-bounces" in self.flags else 0


@dataclass(frozen=True)
class Skip:
    scene: BundledScene
    feature: str
    reason: str

    @property
    def id(self) -> str:
        return f"{self.scene.name}/{self.feature}"


def _typical_bounces(scene: BundledScene) -> int:
    f = scene.flags
    return int(f[f.index("-bounces") + 1]) if "-bounces" in f else DEFAULT_BOUNCES


def case_matrix(scene: BundledScene, info: SceneInfo | None = None) -> tuple[list[Case], list[Skip]]:
    info = info or analyze(load_scene(scene.path))
    n = str(_typical_bounces(scene))
    # (feature, flags, kinds, flags that must matter for the case to exist)
    candidates = [
        ("plain", (), KINDS, ()),
        ("shadows", ("-shadows",), ("color",), ("-shadows",)),
        (f"bounces{n}", ("-bounces", n), ("color",), ("-bounces",)),
        (f"shadows+bounces{n}", ("-shadows", "-bounces", n), ("color",), ("-shadows", "-bounces")),
        ("jitter", ("-jitter",), KINDS, ("-jitter",)),
        ("filter", ("-filter",), KINDS, ("-filter",)),
        ("jitter+filter", ("-jitter", "-filter"), KINDS, ("-jitter", "-filter")),
    ]
    cases, skips = [], []
    for feature, flags, kinds, needs in candidates:
        idle = [f for f in needs if not info.matters(f)]
        if idle:
            reasons = "; ".join(f"{f} has {info.flag_effects[f]}" for f in idle)
            skips.append(Skip(scene, feature, reasons))
        else:
            cases.append(Case(scene, feature, flags, kinds))
    return cases, skips


def kind_skip_reason(feature: str, kind: str) -> str:
    """Why a kind is not compared in a case (shadows and mirrors change only the color)."""
    return f"{feature} does not change the {kind} image (primary hits only)"
