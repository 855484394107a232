"""A submission's results in Gradescope's autograder format (results.json).

The format (https://gradescope-autograders.readthedocs.io/en/latest/specs/): a top-level
`score`, `execution_time` (seconds), `output` and `tests`, each test with `name`, `score`,
`max_score`, `status` ("passed" or "failed"), `output` and `visibility` ("visible",
"hidden", "after_due_date" or "after_published"). Gradescope runs an autograder once per
submission; `raycheck check --gradescope FILE` writes this for one, `raycheck grade` into each
submission's folder.

One test per feature family the scenes exercise: its points times the share of its cases that
pass (as grade scores it), and in its output the cases that did not pass with the top finding
of each, so the student sees which function to look at. A build that failed is one test
worth nothing, holding the compiler's first error."""
from __future__ import annotations

from ..check_options import FAMILIES, feature_family
from ..records import CheckEntry, CheckReport, Verdict

VISIBILITIES = ("visible", "hidden", "after_due_date", "after_published")
MAX_OUTPUT_LINES = 20  # per test: the first failing cases; the report holds every one


def gradescope_results(report: CheckReport | None, points: dict[str, float],
                       families: list[str], *, build: str = "", build_error: str = "",
                       visibility: str = "visible") -> dict:
    """results.json for one submission: `report` is its check (None when it did not build),
    `families` those the scenes exercise (families_of), `build` and `build_error` what its
    build said."""
    tests: list[dict] = []
    if build:
        tests.append({"name": "build", "score": 0.0, "max_score": 0.0,
                      "status": "failed" if build_error else "passed",
                      "output": build_error or build, "visibility": visibility})
    cases = _cases_by_family(report)
    for family in families:
        kinds_of = cases.get(family, {})
        passed = sum(all(k.verdict == Verdict.PASS for k in kinds) for kinds in kinds_of.values())
        total = len(kinds_of)
        share = passed / total if total else 0.0
        lines = [f"{passed} of {total} cases pass"] if report is not None else \
            ["not run: the submission did not build"]
        for (scene, feature), kinds in kinds_of.items():
            failing = next((k for k in kinds if k.verdict != Verdict.PASS), None)
            if failing is None or len(lines) > MAX_OUTPUT_LINES:
                continue
            top = failing.findings[0] if failing.findings else None
            lines.append(f"{scene} {feature} ({failing.kind}): {failing.verdict}"
                         + (f": {top.message}" if top is not None else ""))
        tests.append({"name": family, "score": round(points[family] * share, 4),
                      "max_score": float(points[family]),
                      "status": "passed" if total and passed == total else "failed",
                      "output": "\n".join(lines), "visibility": visibility})
    score = sum(t["score"] for t in tests)
    summary = build_error and f"build failed: {build_error}" or (
        f"{sum(t['score'] for t in tests):g} of {sum(t['max_score'] for t in tests):g} points"
        + (f"; {build}" if build else ""))
    results: dict = {"score": round(score, 4), "output": summary, "visibility": visibility,
                     "stdout_visibility": "hidden", "tests": tests}
    if report is not None:
        results["execution_time"] = round(report.seconds)
    return results


def families_of(report: CheckReport) -> list[str]:
    """The feature families a check's cases exercise, in FAMILIES' order."""
    found = {feature_family(e.feature) for e in report.cases}
    return [f for f in FAMILIES if f in found]


def _cases_by_family(report: CheckReport | None) -> dict[str, dict[tuple[str, str],
                                                                  list[CheckEntry]]]:
    """family -> (scene, feature) -> the case's image kinds; every family with no report."""
    if report is None:
        return {}
    out: dict[str, dict[tuple[str, str], list[CheckEntry]]] = {}
    for entry in report.cases:
        family = feature_family(entry.feature)
        if family is None:
            continue
        out.setdefault(family, {}).setdefault((entry.scene, entry.feature), []).append(entry)
    return out
