"""The class's files that `raycheck grade` writes beside the submissions' folders, each a
function of the class's grades: grades.json (every number, and which submissions make which
mistake), grades.csv (a line per submission, for a gradebook) and the class page
(index.html). A new format is a function here and its entry in CLASS_FILES; each submission's
own results.json is gradescope.py's."""
from __future__ import annotations

import csv
import io
from collections import Counter
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

from raycheck.tracer.mistakes import MistakeError, parse_switch

from ..check_options import FAMILIES
from ..pages.grades import grades_page
from ..records import ClassMistake, GradeRow, json_text, to_json


@dataclass(frozen=True)
class ClassGrades:
    rows: tuple[GradeRow, ...]
    points: dict[str, float]
    seconds: float
    provenance: dict[str, str]


def class_mistakes(rows: tuple[GradeRow, ...]) -> tuple[ClassMistake, ...]:
    """The mistakes found in the class, the most common first, each with who makes it."""
    spelled: dict[str, Counter[str]] = {}
    who: dict[str, list[str]] = {}
    for row in rows:
        for mistake in row.mistakes:
            code = mistake.partition("=")[0]
            spelled.setdefault(code, Counter())[mistake] += 1
            who.setdefault(code, []).append(row.name)
    out = []
    for code, names in who.items():
        try:
            switch = parse_switch(spelled[code].most_common(1)[0][0])
        except MistakeError:  # grades of another catalogue: not described
            continue
        out.append(ClassMistake(code, switch.mistake.function, switch.describe(),
                                tuple(names)))
    return tuple(sorted(out, key=lambda m: (-len(m.submissions), m.mistake)))


def grades_json(grades: ClassGrades) -> str:
    return json_text({"points": grades.points, "submissions": to_json(list(grades.rows)),
                      "mistakes": to_json(list(class_mistakes(grades.rows))),
                      "seconds": grades.seconds, "provenance": grades.provenance})


def grades_csv(grades: ClassGrades) -> str:
    """One line per submission for a gradebook: name, score, per family passed and total,
    how its build went, and the mistakes found (--mistake switches, space-separated)."""
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(["name", "score", "max_score",
                *[f"{f} {c}" for f in FAMILIES for c in ("passed", "total")],
                "cases", "passed", "crashes", "timeouts", "errors", "report", "build",
                "build_error", "mistakes"])
    for r in grades.rows:
        w.writerow([r.name, r.score, r.max_score,
                    *[n for f in FAMILIES for n in (r.families[f].passed, r.families[f].total)],
                    r.cases, r.passed, r.crashes, r.timeouts, r.errors, r.report, r.build,
                    r.build_error, " ".join(r.mistakes)])
    return buf.getvalue()


def class_page(grades: ClassGrades) -> str:
    return grades_page(list(grades.rows), grades.points, grades.provenance,
                       class_mistakes(grades.rows))


CLASS_FILES: dict[str, Callable[[ClassGrades], str]] = {
    "grades.json": grades_json, "grades.csv": grades_csv, "index.html": class_page}


def write_class_files(out: Path, grades: ClassGrades) -> None:
    for name, write in CLASS_FILES.items():
        (out / name).write_text(write(grades), encoding="utf-8")
