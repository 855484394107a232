"""`raycheck autograder`: a Gradescope autograder folder for the course's assignment.

Gradescope (https://gradescope-autograders.readthedocs.io/en/latest/specs/) builds an image
from a zip whose root holds `setup.sh` (run once, as root, on its Ubuntu image) and
`run_autograder` (run once per submission, in /autograder, with the student's files in
/autograder/submission; it must write /autograder/results/results.json). The folder written
here holds both, the raycheck wheel that setup.sh installs, the weights and the teacher's
scene files; run_autograder grades the submission as `raycheck grade` does (built from its
sources in the sandbox where the image allows one: Gradescope's container is the isolation
where it does not) and copies the submission's results.json into place.

`AUTOGRADER` (default /autograder) and `RAYCHECK` (default the venv setup.sh made) in
run_autograder's environment move it elsewhere: a test runs it in a root of its own."""
from __future__ import annotations

import shlex
import shutil
from pathlib import Path

from raycheck.tracer.scene import load_scene

from ..catalog import bundled_path
from ..renderers.command import stage_scene

LLVM_VERSIONS = (20, 19, 18, 17)  # Dr.Jit's CPU backend needs libLLVM 17 or newer

SETUP = """#!/usr/bin/env bash
# Gradescope runs this once, as root, when it builds the autograder's image (Ubuntu): the
# system packages raycheck needs, then raycheck from the wheel beside this file.
set -euo pipefail
apt-get update -qq
DEBIAN_FRONTEND=noninteractive apt-get install -y -qq python3 python3-venv cmake g++ make \\
    git bubblewrap gdb valgrind >/dev/null
llvm=""
for v in {versions}; do
  if apt-cache show "libllvm$v" >/dev/null 2>&1; then
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq "libllvm$v" >/dev/null
    llvm=$v
    break
  fi
done
if [ -z "$llvm" ]; then
  echo "raycheck needs libLLVM 17 or newer; this image's apt sources have none" >&2
  exit 1
fi
if ! python3 -c 'import sys; sys.exit(sys.version_info < (3, 11))'; then
  echo "raycheck needs Python 3.11 or newer (choose Gradescope's Ubuntu 24.04 base image)" >&2
  exit 1
fi
python3 -m venv /autograder/venv
/autograder/venv/bin/pip install --quiet /autograder/source/{wheel}
"""

RUN = """#!/usr/bin/env bash
# Gradescope runs this once per submission: builds /autograder/submission's sources and
# grades them (raycheck grade), then puts the submission's results.json where Gradescope
# reads it. raycheck's own output goes to Gradescope's stdout log, for the instructor.
set -u
AUTOGRADER=${{AUTOGRADER:-/autograder}}
RAYCHECK=${{RAYCHECK:-/autograder/venv/bin/raycheck}}
source="$AUTOGRADER/source"
work=$(mktemp -d)
mkdir -p "$AUTOGRADER/results"
"$RAYCHECK" grade "submission=$AUTOGRADER/submission" {args} --out "$work/class" --quiet
status=$?
if [ -f "$work/class/submission/results.json" ]; then
  cp "$work/class/submission/results.json" "$AUTOGRADER/results/results.json"
else
  printf '{{"score": 0, "output": "The autograder could not grade this submission (raycheck \
grade ended with status %s); the instructor can see why in its output.", "tests": []}}\\n' \\
    "$status" > "$AUTOGRADER/results/results.json"
fi
"""


class AutograderError(ValueError):
    """What cannot go into an autograder folder (one line, exit status 2)."""


def write_autograder(out: Path, wheel: Path, scenes: list[Path], weights: Path | None,
                     size: tuple[int, int] | None, features: str | None,
                     sandbox_read: list[Path]) -> list[Path]:
    """The autograder folder `out` (an empty one, or made here); returns the files it holds.
    Bundled scenes are named (the wheel has them); scene files are copied with what they
    read."""
    if not (wheel.is_file() and wheel.name.startswith("raycheck-") and wheel.suffix == ".whl"):
        raise AutograderError(f"{wheel}: not a raycheck wheel (raycheck-*.whl)")
    out.mkdir(parents=True, exist_ok=True)
    shutil.copyfile(wheel, out / wheel.name)
    args = []
    for k, scene in enumerate(scenes):
        if not Path(scene).exists() and bundled_path(str(scene)):
            args.append(str(scene))
            continue
        load_scene(scene)  # a bad scene fails here, with file and line
        copy = stage_scene(Path(scene), out / "scenes" / f"{k:02d}")
        args.append(f'"$source/{copy.relative_to(out).as_posix()}"')
    scene_args = ["--scenes", *args] if args else []
    if weights is not None:
        shutil.copyfile(weights, out / "weights.toml")
        scene_args += ["--weights", '"$source/weights.toml"']
    if size is not None:
        scene_args += ["--size", str(size[0]), str(size[1])]
    if features:
        scene_args += ["--features", shlex.quote(features)]
    for folder in sandbox_read:
        scene_args += ["--sandbox-read", shlex.quote(str(folder.resolve()))]
    files = {"setup.sh": SETUP.format(versions=" ".join(map(str, LLVM_VERSIONS)),
                                      wheel=wheel.name),
             "run_autograder": RUN.format(args=" ".join(scene_args))}
    for name, text in files.items():
        (out / name).write_text(text, encoding="utf-8")
        (out / name).chmod(0o755)
    return sorted(p for p in out.rglob("*") if p.is_file())
