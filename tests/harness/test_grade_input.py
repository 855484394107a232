"""`raycheck grade`'s input before any work: submissions by file, folder or command string,
named and made unique; weights files; every bad one is one line and exit status 2."""
from __future__ import annotations

import sys
from pathlib import Path

import pytest

from raycheck.harness.cli import main
from raycheck.harness.commands.grade import DEFAULT_POINTS, read_points, submissions
from raycheck.harness.renderers import Limits


def executable(path: Path) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text("#!/bin/sh\nexit 0\n")
    path.chmod(0o755)
    return path


def test_submissions_by_folder_file_and_command_get_unique_names(tmp_path: Path):
    executable(tmp_path / "alice" / "a2")
    bob = executable(tmp_path / "bob.sh")
    script = tmp_path / "carol" / "tracer.py"
    script.parent.mkdir()
    script.write_text("")
    subs = submissions([str(tmp_path / "alice"), str(bob), f"{sys.executable} {script}",
                        f"dave={tmp_path / 'alice'}", str(tmp_path / "alice")], Limits())
    assert [s.name for s in subs] == ["alice", "bob", "tracer", "dave", "alice-2"]
    assert subs[0].renderer.argv == [str(tmp_path / "alice" / "a2")]
    assert subs[2].renderer.identity()["file"] == str(script)


@pytest.mark.parametrize("text, words", [
    ("[points]\nplain = -1\n", "points of plain must be a finite number >= 0, found -1"),
    ("[points]\nshadow = 3\n", "unknown feature families shadow"),
    ("plain = 3\n", "expected one [points] table"),
    ("[points\n", "cannot read the weights"),
    ('[points]\nplain = "ten"\n', "points of plain must be a finite number"),
    ("[points]\nplain = 1e400\n", "points of plain must be a finite number >= 0, found inf"),
    ("[points]\nplain = nan\n", "points of plain must be a finite number >= 0, found nan"),
    ("[points]\nplain = " + "9" * 400 + "\n", "points of plain must be a finite number"),
])
def test_bad_weights_are_one_line_and_exit_2(text, words, tmp_path: Path, capsys):
    weights = tmp_path / "w.toml"
    weights.write_text(text)
    executable(tmp_path / "s" / "a2")
    code = main(["grade", str(tmp_path / "s"), "--weights", str(weights), "--out",
                 str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1 and words in err, err
    assert not (tmp_path / "out").exists()


def test_weights_name_the_points_of_each_family(tmp_path: Path):
    weights = tmp_path / "w.toml"
    weights.write_text('[points]\nplain = 1\n"jitter+filter" = 2.5\n')
    assert read_points(weights) == {f: {"plain": 1.0, "jitter+filter": 2.5}.get(f, 0.0)
                                    for f in DEFAULT_POINTS}


@pytest.mark.parametrize("make, words", [
    (lambda d: d.mkdir(), "a folder without an executable a2"),
    (lambda d: d.write_text(""), "not executable"),
    (lambda d: None, "no such file or command"),
])
def test_bad_submissions_are_one_line_and_exit_2(make, words, tmp_path: Path, capsys):
    make(tmp_path / "sub")
    code = main(["grade", str(tmp_path / "sub"), "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1 and words in err, err
