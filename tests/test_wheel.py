"""The wheel a user installs: built from the repository, installed into a fresh virtual
environment outside it, it holds one top-level import name (raycheck), ships the bundled scenes
and runs gallery, report and check from a folder that knows nothing of the repository."""
from __future__ import annotations

import json
import os
import subprocess
import sys
import sysconfig
import zipfile
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parent.parent
pytestmark = pytest.mark.full  # builds a wheel and a venv: CI's full run


@pytest.fixture(scope="module")
def installed(tmp_path_factory) -> tuple[Path, Path]:
    """(the wheel, the fresh venv's bin folder). The venv gets raycheck from the wheel alone;
    its dependencies come from this environment's site-packages through a .pth line, which
    puts them on sys.path without running this environment's editable-install hook."""
    tmp = tmp_path_factory.mktemp("wheel")
    subprocess.run([sys.executable, "-m", "pip", "wheel", "-q", "--no-deps", str(REPO), "-w",
                    str(tmp / "dist")], check=True, capture_output=True, cwd=tmp)
    wheel = next((tmp / "dist").glob("raycheck-*.whl"))
    venv = tmp / "venv"
    subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(venv)], check=True)
    bin_dir = venv / "bin"
    site = Path(subprocess.run([str(bin_dir / "python"), "-c",
                                "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
                               check=True, capture_output=True, text=True).stdout.strip())
    (site / "dependencies.pth").write_text(sysconfig.get_paths()["purelib"] + "\n")
    subprocess.run([sys.executable, "-m", "pip", "--python", str(bin_dir / "python"), "install",
                    "-q", "--no-deps", str(wheel)], check=True, capture_output=True, cwd=tmp)
    return wheel, bin_dir


def _run(bin_dir: Path, args: list[str], cwd: Path) -> subprocess.CompletedProcess:
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV")}
    return subprocess.run([str(bin_dir / "raycheck"), *args], cwd=cwd, capture_output=True,
                          text=True, env=env, timeout=600)


def test_the_wheel_holds_one_import_name_and_the_scenes(installed):
    wheel, _ = installed
    names = zipfile.ZipFile(wheel).namelist()
    assert {n.split("/")[0] for n in names if not n.startswith("raycheck-")} == {"raycheck"}
    assert "raycheck/scenes/course/arch.txt" in names
    assert "raycheck/scenes/assets/sky/up.png" in names
    shipped = [n for n in names if n.startswith("raycheck/scenes/distributions/")]
    assert "raycheck/scenes/distributions/index.json" in shipped and len(shipped) == 133
    assert "raycheck/harness/cli/__init__.py" in names


def test_installed_commands_find_their_scenes(installed, tmp_path: Path):
    _, bin_dir = installed
    where = _run(bin_dir, ["--version"], tmp_path)
    assert where.returncode == 0 and where.stdout.startswith("raycheck ")
    origin = subprocess.run([str(bin_dir / "python"), "-c",
                             "import raycheck.harness as h; print(h.__file__)"],
                            capture_output=True, text=True, cwd=tmp_path, check=True).stdout
    assert not origin.startswith(str(REPO))  # the installed copy, not the repository

    gallery = _run(bin_dir, ["gallery", "--out", "g", "--size", "8", "8", "--quiet"], tmp_path)
    assert gallery.returncode == 0, gallery.stderr
    assert len(list((tmp_path / "g" / "gallery").glob("*.png"))) == 3 * 7

    report = _run(bin_dir, ["report", "features/shadows", "--out", "r", "--size", "12",
                            "--no-sweeps", "--quiet"], tmp_path)
    assert report.returncode == 0, report.stderr + report.stdout
    data = json.loads((tmp_path / "r" / "report" / "report.json").read_text())
    assert data["summary"]["fail"] == data["summary"]["error"] == 0
    assert data["summary"]["pass"] > 0

    check = _run(bin_dir, ["check", "--renderer", f"{bin_dir / 'python'} -m raycheck.tracer",
                           "course/arch", "--size", "12", "12", "--features", "plain,shadows",
                           "--out", "c", "--quiet"], tmp_path)
    assert check.returncode == 0, check.stderr + check.stdout
    summary = json.loads((tmp_path / "c" / "check.json").read_text())["summary"]
    assert summary == {"pass": 4, "fail": 0, "error": 0}
