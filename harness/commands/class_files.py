"""The class's files that `raycheck grade` writes beside the submissions' folders, each a
function of the class's grades: grades.json (every number), grades.csv (a line per submission,
for a gradebook) and the class page (index.html). A new format is a function here and its
entry in CLASS_FILES; each submission's own results.json is gradescope.py's."""
from __future__ import annotations

import csv
import io
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

from ..check_options import FAMILIES
from ..pages.grades import grades_page
from ..records import GradeRow, json_text, to_json


@dataclass(frozen=True)
class ClassGrades:
    rows: tuple[GradeRow, ...]
    points: dict[str, float]
    seconds: float
    provenance: dict[str, str]


def grades_json(grades: ClassGrades) -> str:
    return json_text({"points": grades.points, "submissions": to_json(list(grades.rows)),
                      "seconds": grades.seconds, "provenance": grades.provenance})


def grades_csv(grades: ClassGrades) -> str:
    """One line per submission for a gradebook: name, score, per family passed and total,
    and how its build went."""
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(["name", "score", "max_score",
                *[f"{f} {c}" for f in FAMILIES for c in ("passed", "total")],
                "cases", "passed", "crashes", "timeouts", "errors", "report", "build",
                "build_error"])
    for r in grades.rows:
        w.writerow([r.name, r.score, r.max_score,
                    *[n for f in FAMILIES for n in (r.families[f].passed, r.families[f].total)],
                    r.cases, r.passed, r.crashes, r.timeouts, r.errors, r.report, r.build,
                    r.build_error])
    return buf.getvalue()


def class_page(grades: ClassGrades) -> str:
    return grades_page(list(grades.rows), grades.points, grades.provenance)


CLASS_FILES: dict[str, Callable[[ClassGrades], str]] = {
    "grades.json": grades_json, "grades.csv": grades_csv, "index.html": class_page}


def write_class_files(out: Path, grades: ClassGrades) -> None:
    for name, write in CLASS_FILES.items():
        (out / name).write_text(write(grades), encoding="utf-8")
