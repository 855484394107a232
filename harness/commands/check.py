"""`raycheck check`: a candidate renderer against the reference, every case of the matrix.

Writes DIR/index.html (the diagnosis of the program, the overview matrix, then every
comparison), DIR/check.json (the candidate's identity, one entry per case and image kind, and
the diagnosis) and DIR/junit.xml; each case's pictures and page under DIR/cases/.
"""
from __future__ import annotations

from pathlib import Path

from ..diagnosis.program import program_diagnosis
from ..pages.diagnosis import diagnosis_html
from ..pages.html import check_intro
from ..pipeline.matrix import (
    Matrix,
    Runner,
    run_matrix,
    summary,
    write_index,
    write_json,
    write_junit,
)
from ..provenance import provenance
from ..records import (
    CaseRecord,
    CheckEntry,
    CheckReport,
    Role,
    SkipRecord,
    to_json,
)


def check_entries(rows: list[CaseRecord]) -> tuple[CheckEntry, ...]:
    """check.json's cases: one entry per case and image kind."""
    return tuple(
        CheckEntry(scene=row.scene, feature=row.feature, flags=row.flags, size=row.size,
                   kind=k.kind, verdict=k.verdict, metrics=k.metrics, failures=k.failures,
                   findings=k.findings, jitter=k.jitter, stderr_tail=row.log,
                   seconds=(row.times.get(Role.CANDIDATE) or {}).get("cold_s"), page=row.page,
                   quirks=row.quirks)
        for row in rows for k in row.kinds)


def run_check(matrix: Matrix, out: Path, runner: Runner | None = None) -> CheckReport:
    prov = provenance()
    rows, skips, seconds = run_matrix(matrix, out, prov, runner=runner)
    return write_check(matrix, out, rows, skips, seconds, prov)


def write_check(matrix: Matrix, out: Path, rows: list[CaseRecord], skips: list[SkipRecord],
                seconds: float, prov: dict[str, str], junit: bool = True) -> CheckReport:
    """check.json, junit.xml and index.html from the case rows; returns check.json's record.
    Shared with the pytest plugin, which passes junit=False: there pytest's --junitxml is the
    JUnit file."""
    labels = {Role.CANDIDATE: matrix.candidate.name, Role.REFERENCE: matrix.reference.name}
    diagnosis = program_diagnosis(rows)
    report = CheckReport(
        renderer=matrix.candidate.identity(), reference=matrix.reference.name,
        reference_identity=matrix.reference.identity(),
        tolerance=matrix.settings.tolerance.describe(),
        cases=check_entries(rows), skipped=tuple(skips),
        summary=summary(rows), seconds=seconds,
        provenance=prov, diagnosis=diagnosis)
    write_json(out / "check.json", to_json(report))
    if junit:
        write_junit(out / "junit.xml", rows, f"raycheck check {matrix.candidate.name}")
    intro = check_intro(matrix.candidate.name, matrix.reference.name,
                        matrix.settings.tolerance.describe(), matrix.settings.realisations,
                        matrix.settings.jitter_test.describe(), junit)
    write_index(out, rows, skips, labels, intro, prov, f"raycheck check: {matrix.candidate.name}",
                head=diagnosis_html(diagnosis, len(rows)))
    return report
