"""The diagnosis of a program over all its cases: the mistakes the cause search found, each
with the cases it explains and the case that shows it most clearly, then the failing cases no
mistake explains with their top finding (where to look, localise.py). What the overview page,
the terminal and check.json open with: a student asks what is wrong with the program, not
which cells are red."""
from __future__ import annotations

from collections import Counter

from raycheck.tracer.mistakes import MistakeError, parse_switch
from raycheck.tracer.quirks import BY_SWITCH

from ..records import CaseRecord, MistakeFound, OpenCase, ProgramDiagnosis, Verdict


def case_name(row: CaseRecord) -> str:
    return f"{row.scene}/{row.feature}"


def program_diagnosis(rows: list[CaseRecord]) -> ProgramDiagnosis:
    """The mistakes found (by code: one mistake may be found at slightly different parameters
    in different cases, named by the value most have), most cases first; then the failing
    cases with a failing kind no cause explains (a case's kinds may have causes of their
    own, one of them none)."""
    failing = [r for r in rows if r.verdict != Verdict.PASS]
    explained: dict[str, list[CaseRecord]] = {}
    spelled: dict[str, Counter[str]] = {}
    for row in failing:
        for cause in row.causes:
            code = cause.partition("=")[0]
            explained.setdefault(code, []).append(row)
            spelled.setdefault(code, Counter())[cause] += 1
    mistakes = []
    for code, cases in explained.items():
        exact = spelled[code].most_common(1)[0][0]
        try:
            switch = parse_switch(exact)
        except MistakeError:  # a results file of another catalogue: its cases stay open
            continue
        # clearest: the mistake alone, reproducing every image, deterministic, most kinds
        best = min(cases, key=lambda r: (len(r.causes) != 1,
                                         not (r.cause is not None and r.cause.reproduces),
                                         r.jittered,
                                         -sum(k.verdict == Verdict.FAIL for k in r.kinds)))
        quirk = BY_SWITCH.get(switch)
        together = sorted({s.partition("=")[0] for r in cases for s in r.causes} - {code})
        mistakes.append(MistakeFound(
            mistake=str(switch), function=switch.mistake.function,
            description=f"your program {switch.describe()}" if quirk is None else
            f"the course program {quirk.course}; your program {quirk.plain} (a quirk of the "
            "course program's: the handouts do not ask for it)", quirk=quirk is not None,
            cases=tuple(case_name(r) for r in cases), together=tuple(together),
            example=case_name(best),
            page=best.page, command=best.cause.command if best.cause else ""))
    mistakes.sort(key=lambda m: (m.quirk, -len(m.cases), m.mistake))
    unexplained = []
    for row in failing:
        # a kind is explained where its top finding is a cause (the case's, or its own)
        kind = next((k for k in row.kinds if k.verdict != Verdict.PASS and not (
            k.findings and k.findings[0].code.startswith("cause:")
            and k.findings[0].code != "cause:unexplained")), None)
        if kind is not None:
            unexplained.append(OpenCase(case_name(row), row.page, kind.kind,
                                        kind.findings[0] if kind.findings else row.error))
    return ProgramDiagnosis(len(failing), tuple(mistakes), tuple(unexplained))
