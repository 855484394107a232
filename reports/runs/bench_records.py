"""A `raycheck bench` run as typed records (records.py's to_json / from_json): what `--json`
writes and docs/bench.json holds, and what the benchmark page, the generated performance
tables and `raycheck report --bench FILE` read back. A saved run may hold only some of the
tables (the course scenes' always)."""
from __future__ import annotations

import statistics
from dataclasses import dataclass, field
from typing import Any

from ..records import from_json, optional, to_json
from .throughput import ThroughputRow

# the targets of issue 17: whole processes at 800x800 at least 5x faster than the course
# program, and at 200x200 no slower where the course program takes more than 0.3 s
VERSUS_GOALS = {800: (5.0, 0.0), 200: (1.0, 0.3)}  # size -> (speed-up, only above these a2 s)


@dataclass(frozen=True)
class Timing:
    """One course scene in one renderer: a fresh process with an empty kernel cache."""

    scene: str
    renderer: str
    size: int
    flags: str
    cold_s: float
    warm_s: float
    warm_runs: int | None = optional("the warm renders' count (runs saved before: none)")


def _derived() -> Any:
    """A field computed from the others (__post_init__): written to JSON, never read."""
    return field(init=False, metadata={"doc": "derived from the other fields", "json": None})


@dataclass(frozen=True)
class Versus:
    """The tracer's command line and another course program, whole processes in pairs."""

    scene: str
    size: int
    flags: str
    tracer_s: tuple[float, ...]  # every paired run, in order
    other_s: tuple[float, ...]
    tracer_median_s: float = _derived()
    other_median_s: float = _derived()
    goal: str = _derived()  # met, missed, or - where VERSUS_GOALS has none for the size

    def __post_init__(self) -> None:
        tracer, other = statistics.median(self.tracer_s), statistics.median(self.other_s)
        object.__setattr__(self, "tracer_median_s", tracer)
        object.__setattr__(self, "other_median_s", other)
        speedup, above_s = VERSUS_GOALS.get(self.size, (0.0, float("inf")))
        object.__setattr__(self, "goal", "-" if other <= above_s else
                           "met" if other / tracer >= speedup else "missed")


@dataclass(frozen=True)
class LoadAverage:
    min: float
    max: float
    every_s: float
    samples: tuple[float, ...]


@dataclass(frozen=True)
class Machine:
    """The machine a run timed, as the performance tables name it."""

    cpu: str
    cores: int
    load_average: LoadAverage  # the 1-minute load average, sampled during the run
    date: str  # UTC, YYYY-MM-DD
    gpu: str  # CUDA, or none


@dataclass(frozen=True)
class BenchRun:
    course: tuple[Timing, ...]
    throughput: tuple[ThroughputRow, ...] | None = optional("primary-ray throughput")
    versus: tuple[Versus, ...] | None = optional("against another course program")
    versus_program: dict[str, Any] | None = optional("that program's identity and name")
    provenance: dict[str, Any] | None = optional("the run's versions and machine")
    machine: Machine | None = optional("where it ran")

    def to_json(self) -> dict:
        return to_json(self)

    @classmethod
    def from_json(cls, data: Any) -> BenchRun:
        """ValueError naming the key where data is not a bench run."""
        return from_json(cls, data)
