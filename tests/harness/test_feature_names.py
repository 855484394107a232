"""Feature names: a family (shadows+bounces) and a case's own name (shadows+bounces4, with
the scene's bounce count) mean the same wherever features are named: --features of check and
grade, the pytest plugin's --raycheck-features and grade's weights."""
from __future__ import annotations

from pathlib import Path

import pytest

from raycheck.harness.check_options import FAMILIES, feature_family
from raycheck.harness.cli import main
from raycheck.harness.commands.grade import GradeInputError, read_points

REPO = Path(__file__).resolve().parents[2]
ARCH = REPO / "scenes" / "course" / "arch.txt"  # its mirror cases are bounces3


@pytest.mark.parametrize("name, family", [
    *[(f, f) for f in FAMILIES],
    ("bounces4", "bounces"), ("bounces12", "bounces"), ("shadows+bounces4", "shadows+bounces"),
    ("bounces3+shadows", "shadows+bounces"), ("filter+jitter", "jitter+filter"),
    (" shadows ", "shadows"),
    ("bounces-1", None), ("bouncesfour", None), ("bounces٣", None), ("shadows+shadows", None),
    ("plain+shadows", None), ("Shadows", None), ("", None), ("jitter+filter+shadows", None),
])
def test_a_case_name_and_its_family_name_one_family(name, family):
    assert feature_family(name) == family


def test_check_runs_a_family_named_by_a_case_name(tmp_path, capsys):
    out = tmp_path / "check"
    code = main(["check", "--renderer", "tracer", str(ARCH), "--out", str(out), "--size", "8",
                 "8", "--features", "shadows+bounces4,plain", "--quiet", "-j", "1"])
    table = capsys.readouterr().out
    assert code == 0, table
    rows = [line.split()[:2] for line in table.splitlines()[1:] if line.startswith("course/")]
    assert rows == [["course/arch", "plain"], ["course/arch", "shadows+bounces3"]]


def test_weights_take_a_case_name_for_its_family(tmp_path):
    weights = tmp_path / "w.toml"
    weights.write_text('[points]\n"shadows+bounces4" = 7\nbounces3 = 2\n')
    points = read_points(weights)
    assert points == {f: {"shadows+bounces": 7.0, "bounces": 2.0}.get(f, 0.0) for f in FAMILIES}


def test_weights_may_not_name_a_family_twice(tmp_path):
    weights = tmp_path / "w.toml"
    weights.write_text('[points]\nbounces = 1\nbounces4 = 2\n')
    with pytest.raises(GradeInputError, match="bounces4 and another key both name the family "
                                              "bounces"):
        read_points(weights)
