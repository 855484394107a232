"""tools/bench_findings.py runs its defects in worker processes (-j): the same table as in one
process, in the defects' order."""
from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
TOOL = REPO / "tools" / "bench_findings.py"
SCENES = [str(REPO / "scenes" / "course" / "spheres_mirror.txt"),
          str(REPO / "scenes" / "features" / "triangle.txt")]


def run(tmp_path: Path, jobs: str) -> tuple[subprocess.CompletedProcess, dict | None]:
    out = tmp_path / f"findings-{jobs}.json"
    proc = subprocess.run([sys.executable, str(TOOL), "--defects", "flip,none,no_shadows",
                           "--size", "16", "-j", jobs, "--json", str(out), *SCENES],
                          capture_output=True, text=True, timeout=300)
    return proc, json.loads(out.read_text()) if out.exists() else None


def test_workers_give_the_table_of_one_process(tmp_path: Path):
    (one, one_json), (two, two_json) = run(tmp_path, "1"), run(tmp_path, "2")
    assert one.returncode == two.returncode == 0, one.stderr + two.stderr
    # flip breaks both scenes' plain cases, 3 kinds each; no_shadows the color of
    # spheres_mirror's shadows and shadows+bounces cases (at 16x16 triangle's shadow covers
    # no pixel)
    expected = [{"defect": "flip", "failing": 6, "named": 6, "seen": {"flipped_vertical": 6}},
                {"defect": "none", "failing": 0, "named": 0, "seen": {}},
                {"defect": "no_shadows", "failing": 2, "named": 2,
                 "seen": {"cause:shadow_missing": 2}}]
    assert one_json["rows"] == two_json["rows"] == expected
    first, _, rest = two.stdout.partition("\n\n")
    table = [line.split(" | ")[0] for line in first.splitlines() if line.startswith("| ")]
    assert table == ["| defect", "| flip", "| none (the tracer)", "| no_shadows"]
    # each top finding's precision over the defects: both named their defect every time
    assert [line for line in rest.splitlines() if line.startswith("| `")] == [
        "| `flipped_vertical` | 6 | 6 | 100% |", "| `cause:shadow_missing` | 2 | 2 | 100% |"]
    assert two_json["precision"] == {"flipped_vertical": {"shown": 6, "right": 6},
                                     "cause:shadow_missing": {"shown": 2, "right": 2}}


def test_a_worker_count_below_one_is_a_usage_error(tmp_path: Path):
    proc, data = run(tmp_path, "0")
    assert proc.returncode == 2 and data is None
    assert "-j 0: at least 1" in proc.stderr and "Traceback" not in proc.stderr
