"""Gradescope's results.json format, as its specification documents it, for the tests."""
from __future__ import annotations

from raycheck.harness.commands.gradescope import VISIBILITIES

# the fields and types of https://gradescope-autograders.readthedocs.io/en/latest/specs/
TOP = {"score": (int, float), "execution_time": (int,), "output": (str,),
       "output_format": (str,), "visibility": (str,), "stdout_visibility": (str,),
       "extra_data": (dict,), "tests": (list,), "leaderboard": (list,)}
TEST = {"score": (int, float), "max_score": (int, float), "status": (str,), "name": (str,),
        "name_format": (str,), "number": (str,), "output": (str,), "output_format": (str,),
        "tags": (list,), "visibility": (str,), "extra_data": (dict,)}


def gradescope_problems(data: dict) -> list[str]:
    """What in `data` is not Gradescope's results.json format."""
    problems = []

    def typed(record: dict, fields: dict, where: str) -> None:
        for key, value in record.items():
            if key not in fields:
                problems.append(f"{where}: unknown field {key}")
            elif isinstance(value, bool) or not isinstance(value, fields[key]):
                problems.append(f"{where}: {key} is {type(value).__name__}")
        if record.get("visibility", "visible") not in VISIBILITIES:
            problems.append(f"{where}: visibility {record['visibility']}")

    typed(data, TOP, "results")
    if "score" not in data and any("score" not in t for t in data.get("tests", [])):
        problems.append("results: no score, and a test without one")
    if data.get("stdout_visibility", "visible") not in VISIBILITIES:
        problems.append("results: stdout_visibility")
    for k, test in enumerate(data.get("tests", [])):
        typed(test, TEST, f"test {k}")
        if test.get("status", "passed") not in ("passed", "failed"):
            problems.append(f"test {k}: status {test['status']}")
    return problems
