"""How the cases of a run are judged and diagnosed: one record, made from the check's (or the
report's, or grade's) configuration and carried whole through the matrix and each job to the
case, so that no function takes these settings one by one and none is dropped on the way."""
from __future__ import annotations

from dataclasses import dataclass

from .judge.statistics import JitterTest
from .judge.verdict import Tolerance
from .storage.distribution import DEFAULT_REALISATIONS


@dataclass(frozen=True)
class CaseSettings:
    tolerance: Tolerance = Tolerance()  # deterministic images: per pixel, share, hard limit
    warm: bool = False  # time a second, warm render of each case (the report's time columns)
    realisations: int = DEFAULT_REALISATIONS  # K of a jittered case's reference distribution
    jitter_test: JitterTest = JitterTest()  # how jittered images are judged
    causes: bool = True  # failing images go through the cause search (diagnosis/causes.py)
    strict: bool = False  # an image off only by the course program's quirks fails (quirks.py)

    def key(self) -> tuple:
        """What a case's result depends on, for the result cache's key."""
        return (self.tolerance.describe(), self.warm, self.realisations,
                self.jitter_test.describe(), self.causes, self.strict)
