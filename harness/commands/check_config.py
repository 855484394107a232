"""What a check runs, as one record: `raycheck check`, the pytest plugin and `raycheck grade`
each build a CheckConfig from their own options and get the same validated Matrix from it.

    config = CheckConfig(renderer="python3 my_tracer.py", features="shadows,jitter")
    matrix = config.matrix()          # ConfigError("features", ...) for a bad one

A ConfigError names the option by its field; each front end spells it as its users typed it
(`--fail-share` on the command line, `--raycheck-features` in pytest)."""
from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path
from typing import TypeVar

from raycheck.tracer.scene.limits import (
    DEFAULT_MAX_KERNEL_TESTS,
    DEFAULT_MAX_MEMORY,
    DEFAULT_MAX_RAYS,
    Budget,
)

from ..case_settings import CaseSettings
from ..check_options import DEFAULT_TIMEOUT_S, FEATURES_HELP, ConfigError, feature_family
from ..judge.verdict import Tolerance
from ..pipeline.matrix import Matrix
from ..renderers import BUILTIN, CommandRenderer, Limits, Renderer, renderer_from_spec
from ..renderers.sandbox import (
    Sandbox,
    SandboxError,
    SandboxMode,
    sandbox_for,
    unavailable_reason,
)
from ..storage.distribution import DEFAULT_REALISATIONS

R = TypeVar("R", bound=Renderer)

@dataclass(frozen=True)
class CheckConfig:
    renderer: str | None = None  # the candidate's spec: a command, or tracer / mitsuba
    reference: str = "tracer"  # what it is judged against (renderers.BUILTIN)
    scenes: tuple[Path, ...] = ()  # files or bundled names (course/arch); () every bundled one
    size: tuple[int, int] | None = None  # every case's size; None: each scene's own
    features: str | None = None  # comma-separated families or case names; None: all
    timeout: float = DEFAULT_TIMEOUT_S  # wall-clock seconds per render of the candidate
    tolerance: int = Tolerance.levels  # per-pixel tolerance in 8-bit levels
    fail_share: float = Tolerance.share  # share of pixels allowed beyond it
    hard_limit: int | None = Tolerance.hard  # no pixel beyond this many levels (None: off)
    max_memory: int | None = None  # bytes a render may use (None: limits' default)
    max_rays: int = DEFAULT_MAX_RAYS
    max_kernel_tests: int = DEFAULT_MAX_KERNEL_TESTS
    realisations: int = DEFAULT_REALISATIONS  # K of the jittered cases' reference
    causes: bool = True  # failing images go through the cause search (diagnosis/causes.py)
    strict: bool = False  # the course program's quirks count (diagnosis/quirks.py)
    sandbox: SandboxMode = SandboxMode.OFF  # how a candidate program runs (renderers/sandbox.py)
    sandbox_read: tuple[Path, ...] = ()  # more folders the sandbox shows it, read-only

    def sandboxed(self, candidate: R) -> R:
        """The candidate in the sandbox that `sandbox` asks for, where it is a program (the
        builtin renderers run in this process); ConfigError for required where bubblewrap
        cannot run."""
        if not isinstance(candidate, CommandRenderer) or candidate.sandbox is not None:
            return candidate
        return replace(candidate, sandbox=self.box())

    def box(self) -> Sandbox | None:
        """The sandbox programs run in (None: rlimits only); ConfigError for required where
        bubblewrap cannot run."""
        try:
            return sandbox_for(self.sandbox, tuple(p.resolve() for p in self.sandbox_read))
        except SandboxError as e:
            raise ConfigError("sandbox", str(e)) from None

    def sandbox_warning(self) -> str | None:
        """What to say once where --sandbox auto found no sandbox (candidates then run with
        rlimits only)."""
        if self.sandbox != SandboxMode.AUTO or sandbox_for(SandboxMode.AUTO) is not None:
            return None
        return (f"warning: no sandbox ({unavailable_reason()}): candidate programs run with "
                "resource limits only (--sandbox required makes this an error)")

    def budget(self) -> Budget:
        return Budget(self.max_memory or DEFAULT_MAX_MEMORY, self.max_rays,
                      self.max_kernel_tests)

    def families(self) -> frozenset[str] | None:
        """The feature families asked for (None: every one)."""
        if not self.features:
            return None
        names = [f.strip() for f in self.features.split(",") if f.strip()]
        if not names:
            raise ConfigError("features", f"no feature named (expected some of {FEATURES_HELP})")
        families = {n: feature_family(n) for n in names}
        unknown = [n for n, family in families.items() if family is None]
        if unknown:
            raise ConfigError("features", f"unknown {', '.join(unknown)} "
                                          f"(expected some of {FEATURES_HELP})")
        return frozenset(f for f in families.values() if f is not None)

    def matrix(self, candidate: Renderer | None = None) -> Matrix:
        """The validated matrix (scenes parsed, with file and line for a bad one, before any
        work); `candidate` stands in for `renderer` where the caller built it (grade's
        submissions)."""
        self._check_numbers()
        families = self.families()
        if self.reference not in BUILTIN:
            raise ConfigError("reference", f"expected one of {', '.join(sorted(BUILTIN))}, "
                                           f"found {self.reference}")
        from ..catalog import scenes_named

        scenes = scenes_named(list(self.scenes))
        if candidate is None:
            if self.renderer is None:
                raise ConfigError("renderer", "the candidate's command is required")
            try:
                candidate = renderer_from_spec(self.renderer, Limits(timeout_s=self.timeout),
                                               self.budget())
            except ValueError as e:
                raise ConfigError("renderer", str(e)) from None
        candidate = self.sandboxed(candidate)
        reference = renderer_from_spec(self.reference, budget=self.budget())
        return Matrix(scenes, candidate, reference, self.settings(), self.size,
                      features=families, budget=self.budget())

    def settings(self) -> CaseSettings:
        """How each case is judged and diagnosed."""
        return CaseSettings(Tolerance(self.tolerance, self.fail_share, self.hard_limit),
                            realisations=self.realisations, causes=self.causes,
                            strict=self.strict)

    def _check_numbers(self) -> None:
        if self.size is not None and (len(self.size) != 2 or min(self.size) < 1):
            raise ConfigError("size", f"expected W H, two integers >= 1, found "
                                      f"{' '.join(map(str, self.size))}")
        if not self.timeout > 0:
            raise ConfigError("timeout", f"expected a number of seconds > 0, found "
                                         f"{self.timeout:g}")
        if self.tolerance < 0:
            raise ConfigError("tolerance", f"expected levels >= 0, found {self.tolerance}")
        if not 0 <= self.fail_share <= 1:
            raise ConfigError("fail_share", f"expected a share in 0..1, found {self.fail_share:g}")
        if self.hard_limit is not None and self.hard_limit < 0:
            raise ConfigError("hard_limit", f"expected levels >= 0, found {self.hard_limit}")
        if self.realisations < 4:
            raise ConfigError("realisations", f"expected at least 4, found {self.realisations}")
        for name in ("max_rays", "max_kernel_tests"):
            if getattr(self, name) < 1:
                raise ConfigError(name, f"expected at least 1, found {getattr(self, name)}")
