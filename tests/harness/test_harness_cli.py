"""Hostile input for the harness commands (report, compare, check, stress, bench, gallery,
info, export): every failure is one line on stderr with exit status 2 and no traceback, before
any work where it can be; an output folder that cannot be written (a file, a full disk, no
permission) leaves the previous one whole; help and version on every command."""
from __future__ import annotations

import errno
import json
from pathlib import Path

import pytest

from raycheck.harness.cli import COMMANDS, main

REPO = Path(__file__).resolve().parents[2]
SHADOWS = REPO / "scenes" / "features" / "shadows.txt"
ARCH = REPO / "scenes" / "course" / "arch.txt"


def run(argv: list, capsys) -> tuple[int, str, str]:
    code = main([str(a) for a in argv])
    out = capsys.readouterr()
    return code, out.out, out.err


def assert_usage_error(code: int, err: str, prog: str, *words: str) -> None:
    assert code == 2, err
    assert err.count("\n") == 1 and err.startswith(f"raycheck {prog}: error: "), err
    assert "Traceback" not in err
    for w in words:
        assert w in err, err


@pytest.mark.parametrize("argv, words", [
    (["compare", "-input", ARCH, "-size", 16385, 1, "--out", "o"], ["16385x1", "1..16384"]),
    (["compare", "-input", ARCH, "-bounces", 65, "--out", "o"], ["bounces 65", "0..64"]),
    (["compare", "-input", ARCH, "-size", 8, 8], ["--out DIR is required"]),
    (["compare", "-input", ARCH, "--out", ""], ["--out"]),
    (["report", "--size", 0], ["--size", "'0'"]),
    (["report", "--size", -3], ["--size"]),
    (["report", "--seed", -1], ["--seed", "'-1'"]),
    (["report", "nonexist.txt"], ["nonexist.txt"]),
    (["report", "--findings", "nonexist.json"],
     ["nonexist.json: not a tools/bench_findings.py --json file"]),
    (["bench", "--size", 0], ["--size"]),
    (["bench", "--json", "/nonexist/x.json"], ["/nonexist"]),
    (["bench", "--versus", " "], ["--versus", "expected a command"]),
    (["bench", "--versus", "./a2", "--throughput"], ["--versus", "cannot run", "./a2"]),
    (["bench", "--versus", "./a2", "--runs", 0], ["--runs"]),
    (["stress", "--scene", "nonexist"], ["no extreme scene named nonexist"]),
    (["check", "--out", "o"], ["--renderer"]),
    (["check", "--renderer", "", "--out", "o"], ["--renderer", "empty"]),
    (["check", "--renderer", "x", "--out", "o", "--features", "plain,nope"], ["nope"]),
    (["check", "--renderer", "x", "--out", "o", "--timeout", 0], ["--timeout"]),
    (["info", "a.png"], ["must end in .txt"]),
    (["export", ARCH, "-input", SHADOWS, "-o", "x.xml"], ["two scenes"]),
])
def test_bad_usage_is_one_line_and_status_2_before_any_work(argv, words, capsys, tmp_path,
                                                           monkeypatch):
    monkeypatch.chdir(tmp_path)
    code, _, err = run(argv, capsys)
    assert_usage_error(code, err, argv[0], *words)
    assert list(tmp_path.iterdir()) == []  # nothing written


@pytest.mark.parametrize("argv", [
    ["gallery", "--out", "{file}"], ["stress", "--out", "{file}"], ["report", "--out", "{file}"],
    ["compare", "-input", ARCH, "--out", "{file}"],
    ["check", "--renderer", "tracer", "--out", "{file}"],
    ["bench", "--html", "{file}"],
])
def test_out_that_is_a_file_is_refused(argv, capsys, tmp_path):
    file = tmp_path / "afile"
    file.write_text("mine")
    code, _, err = run([str(a).replace("{file}", str(file)) for a in argv], capsys)
    assert_usage_error(code, err, argv[0], "not a folder")
    assert file.read_text() == "mine"


@pytest.mark.parametrize("header, words", [
    ("# size: abc\n", ["s.txt:1", "bad '# size:' line"]),
    ("# flags: -depth 5\n", ["s.txt:1", "bad '# flags:' line"]),
    ("# what\n# flags: -bounces two\n", ["s.txt:2", "-bounces"]),
])
def test_a_malformed_scene_header_is_an_input_error(header, words, capsys, tmp_path):
    scene = tmp_path / "scenes" / "s.txt"
    scene.parent.mkdir()
    scene.write_text(header + SHADOWS.read_text().replace("../assets", str(REPO / "scenes/assets")))
    for argv in (["compare", "-input", scene, "-size", 4, 4, "--out", tmp_path / "c"],
                 ["report", scene, "--out", tmp_path / "r", "--size", 4, "--no-sweeps"]):
        code, _, err = run(argv, capsys)
        assert_usage_error(code, err, argv[0], *words)
    assert not (tmp_path / "c").exists() and not (tmp_path / "r").exists()


def _disk_fills_after(monkeypatch, writes: int, error: int) -> None:
    """PNG writes fail with `error` (ENOSPC: a full disk, EACCES: no permission) once
    `writes` of them succeeded."""
    from PIL import Image

    save = Image.Image.save
    count = {"n": 0}

    def failing_save(self, fp, *args, **kwargs):
        count["n"] += 1
        if count["n"] > writes:
            raise OSError(error, "No space left on device" if error == errno.ENOSPC
                          else "Permission denied", str(fp))
        return save(self, fp, *args, **kwargs)

    monkeypatch.setattr(Image.Image, "save", failing_save)


@pytest.mark.parametrize("error", [errno.ENOSPC, errno.EACCES])
def test_a_write_failing_midway_keeps_the_previous_check_whole(error, capsys, tmp_path,
                                                               monkeypatch):
    out = tmp_path / "check"
    argv = ["check", "--renderer", "tracer", SHADOWS, "--size", 8, 8, "--features",
            "plain,shadows", "--out", out, "--quiet"]
    code, _, _ = run(argv, capsys)
    assert code == 0
    before = sorted(p.relative_to(out) for p in out.rglob("*"))
    summary = (out / "check.json").read_text()
    _disk_fills_after(monkeypatch, 5, error)
    code, _, err = run(argv, capsys)
    assert code == 2 and err.count("\n") == 1 and "Traceback" not in err, err
    assert ("No space left" if error == errno.ENOSPC else "Permission denied") in err
    assert sorted(p.relative_to(out) for p in out.rglob("*")) == before
    assert (out / "check.json").read_text() == summary
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith(".check.new")] == []


def test_a_failing_comparison_makes_report_exit_1(capsys, tmp_path):
    # offset_1e7: course mode misses in float32 what Mitsuba hits (docs/exactness.md: robust mode)
    scene = REPO / "scenes" / "extreme" / "offset_1e7.txt"
    code, out, err = run(["report", scene, "--out", tmp_path, "--size", 8, "--no-sweeps",
                          "--quiet"], capsys)
    data = json.loads((tmp_path / "report" / "report.json").read_text())
    assert data["summary"]["fail"] > 0
    assert code == 1 and err == "", err
    assert f"{data['summary']['fail']} failed" in out


def test_stress_exits_0_when_robust_mode_passes(capsys, tmp_path):
    code, out, err = run(["stress", "--scene", "size_1x1", "--no-mitsuba", "--out", tmp_path,
                          "--quiet"], capsys)
    assert code == 0 and err == "", err
    assert (tmp_path / "report" / "stress.html").is_file()


@pytest.mark.parametrize("command", list(COMMANDS))
def test_every_command_has_help_and_a_version(command, capsys):
    code, out, err = run([command, "--help"], capsys)
    assert code == 0 and err == ""
    assert out.startswith("usage: ") and len(out.splitlines()) > 3
    code, out, _ = run(["help", command], capsys)
    assert code == 0 and out.startswith("usage: ")


def test_raycheck_alone_is_a_usage_error_and_help_is_not(capsys):
    code, out, err = run([], capsys)
    assert code == 2 and out == "" and err.startswith("usage: raycheck COMMAND")
    code, out, err = run(["--help"], capsys)
    assert code == 0 and err == "" and all(c in out for c in COMMANDS)
    code, out, _ = run(["--version"], capsys)
    assert code == 0 and out.startswith("raycheck 0.")
    code, _, err = run(["nope"], capsys)
    assert code == 2 and err.count("\n") == 1 and "unknown command 'nope'" in err


def test_course_flag_commands_take_help_anywhere(capsys):
    for command in ("render", "reference", "compare"):
        code, out, err = run([command, "-input", ARCH, "-size", 4, 4, "--help"], capsys)
        assert code == 0 and err == "" and "-bounces n" in out and "--" in out


def test_scenes_of_one_name_in_different_folders_keep_their_own_cases(capsys, tmp_path):
    text = SHADOWS.read_text().replace("../assets", str(REPO / "scenes/assets"))
    for top in ("a", "b"):
        (tmp_path / top / "x").mkdir(parents=True)
        (tmp_path / top / "x" / "s.txt").write_text(text)
    code, _, err = run(["check", "--renderer", "tracer", tmp_path / "a/x/s.txt",
                        tmp_path / "b/x/s.txt", "--size", 6, 6, "--features", "plain",
                        "--out", tmp_path / "out", "--quiet"], capsys)
    assert code == 0, err
    data = json.loads((tmp_path / "out" / "check.json").read_text())
    assert sorted({c["scene"] for c in data["cases"]}) == ["a/x/s", "b/x/s"]
    assert sorted(p.name for p in (tmp_path / "out" / "cases").iterdir()) == ["a_x_s", "b_x_s"]
