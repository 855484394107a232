"""`raycheck check` of jittered cases against wrapper candidates with one jitter defect each
(tests/wrappers/corrupt.py): each fails (the tracer itself passes: test_check.py) the color
image by the statistic that shows its
defect. The shadows scene at 24x24 against 16 realisations of the tracer: its box and sphere
edges run along rows and columns, where a shared jitter pattern makes neighbours err alike.
Candidates and reference seeds are fixed, so every verdict here is reproducible."""
from __future__ import annotations

from pathlib import Path

import pytest
from test_check import SHADOWS, corrupt, run_check

SIZE = ("24", "24")


def failed_statistics(tmp_path: Path, defect: str) -> dict[str, list[str]]:
    """kind -> names of the failing statistics of the shadows jitter case."""
    got = run_check(tmp_path, corrupt(defect), [SHADOWS], "jitter", "--realisations", "16",
                    size=SIZE)
    assert got.code == 1
    return {c["kind"]: [s["name"] for s in c["jitter"]["statistics"] if not s["passed"]]
            for c in got.data["cases"]}


@pytest.mark.parametrize("defect, statistic", [
    ("no_jitter", "mean z^2"),       # the pixel corner decides: far from the jittered spread
    ("samples4", "mean z^2"),        # 4 samples: 4 times the variance
    ("shared_pattern", "correlation"),  # neighbours along an edge err alike
])
def test_jitter_defect_fails_by_its_statistic(tmp_path: Path, defect: str, statistic: str):
    failed = failed_statistics(tmp_path, defect)
    assert statistic in failed["color"], failed

