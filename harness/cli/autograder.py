"""`raycheck autograder --out DIR`: a Gradescope autograder folder
(harness/commands/autograder.py)."""
from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
from pathlib import Path

from .common import (
    UsageError,
    add_case_size_option,
    out_folder,
    run,
)
from .common import (
    parser as command_parser,
)

PROG = "raycheck autograder"
WHEEL_TIMEOUT_S = 600


def parser() -> argparse.ArgumentParser:
    ap = command_parser(
        PROG, "Write a Gradescope autograder folder: setup.sh (installs raycheck and its "
        "system packages on Gradescope's Ubuntu image), run_autograder (builds the "
        "submission's sources from /autograder/submission, grades them as raycheck grade "
        "does and writes /autograder/results/results.json), the raycheck wheel, the weights "
        "and the scenes. Zip the folder's contents (not the folder) and upload it.",
        epilog="Exit status: 0 the folder was written, 2 bad usage or input.")
    ap.add_argument("--out", type=out_folder, required=True, metavar="DIR",
                    help="the autograder folder (replaced if it exists)")
    ap.add_argument("--scenes", nargs="+", type=Path, metavar="SCENE", default=[],
                    help="scene files (copied in, with what they read) or bundled scenes by "
                         "name (course/arch); default: every bundled course and feature scene")
    ap.add_argument("--weights", type=Path, metavar="FILE",
                    help="points per feature family (TOML, as raycheck grade reads it)")
    add_case_size_option(ap)
    ap.add_argument("--features", metavar="LIST", help="the features to grade (default: all)")
    ap.add_argument("--sandbox-read", action="append", type=Path, default=[], metavar="DIR",
                    help="a folder the sandboxed programs may read (raycheck grade's option)")
    ap.add_argument("--wheel", type=Path, metavar="FILE",
                    help="the raycheck wheel to install (default: built from this checkout)")
    return ap


def main(argv: list[str]) -> int:
    args = parser().parse_args(argv)

    def autograder() -> int:
        from ..commands.autograder import AutograderError, write_autograder
        from ..commands.grade import GradeInputError, read_points
        from ..storage.staging import ReplacedFolder

        try:
            if args.weights is not None:
                read_points(args.weights)  # a bad file fails here, not on Gradescope
        except GradeInputError as e:
            raise UsageError(str(e)) from None
        with tempfile.TemporaryDirectory(prefix="raycheck-wheel-") as tmp:
            wheel = args.wheel or built_wheel(Path(tmp))
            try:
                with ReplacedFolder(args.out, finishes_run=True) as staging:
                    files = write_autograder(staging, wheel, args.scenes, args.weights,
                                             tuple(args.size) if args.size else None,
                                             args.features, args.sandbox_read)
            except AutograderError as e:
                raise UsageError(str(e)) from None
        for path in files:
            print(args.out / path.relative_to(staging))
        print(f"autograder folder: {args.out.resolve()} (zip its contents for Gradescope)")
        return 0

    return run(PROG, autograder)


def built_wheel(folder: Path) -> Path:
    """A wheel of the raycheck this runs from, where that is a checkout (an editable install);
    UsageError elsewhere (--wheel names one)."""
    import raycheck.harness

    root = Path(raycheck.harness.__file__).resolve().parent.parent
    project = root / "pyproject.toml"
    if not (project.is_file() and 'name = "raycheck"' in project.read_text(encoding="utf-8")):
        raise UsageError("raycheck is not running from a checkout: name its wheel with --wheel")
    print(f"building the raycheck wheel from {root}", file=sys.stderr)
    run_ = subprocess.run([sys.executable, "-m", "pip", "wheel", "--quiet", "--no-deps",
                           str(root), "-w", str(folder)], capture_output=True, text=True,
                          cwd=folder, timeout=WHEEL_TIMEOUT_S)
    wheels = list(folder.glob("raycheck-*.whl"))
    if run_.returncode != 0 or not wheels:
        last = (run_.stderr.strip().splitlines() or ["no wheel made"])[-1]
        raise UsageError(f"cannot build the raycheck wheel from {root}: {last}")
    return wheels[0]
