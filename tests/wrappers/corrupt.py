"""A course renderer with one known defect: `corrupt.py DEFECT <course flags>` runs the
reference tracer (`python -m raycheck.tracer`, in this process) on the flags, then breaks its output.

Defects: none (the tracer as it is), no_shadows (drops -shadows), filter_2x (the color image
of a -filter render twice as bright, clipped at 255), flip (every image upside down),
no_normals (drops -normals FILE), exit3 (renders, then exits with status 3), sleep (sleeps a
minute, writes nothing), truncate (the color PNG cut to half its bytes), double_size (renders
2W x 2H), segv (kills itself with SIGSEGV before writing anything); jitter defects: no_jitter
(drops -jitter: one sample per pixel), samples4 (4 jittered samples: --samples 4, which the
course command line lacks), shared_pattern (one jitter pattern for every pixel:
tools/jitter_defects.py).
"""
from __future__ import annotations

import os
import signal
import sys
import time
from pathlib import Path

DEFECTS = ("none", "no_shadows", "filter_2x", "flip", "no_normals", "exit3", "sleep",
           "truncate", "double_size", "segv", "no_jitter", "samples4", "shared_pattern")
REPO = Path(__file__).resolve().parents[2]


def outputs(argv: list[str]) -> dict[str, Path]:
    """The image files the course flags name, by kind."""
    files = {}
    for i, a in enumerate(argv):
        if a == "-output":
            files["color"] = Path(argv[i + 1])
        elif a == "-normals":
            files["normals"] = Path(argv[i + 1])
        elif a == "-depth":
            files["depth"] = Path(argv[i + 3])
    return files


def without(argv: list[str], flag: str, values: int) -> list[str]:
    """argv without `flag` and the `values` arguments after it."""
    if flag not in argv:
        return argv
    i = argv.index(flag)
    return argv[:i] + argv[i + 1 + values:]


def rewrite(path: Path, change) -> None:
    import numpy as np
    from PIL import Image

    with Image.open(path) as im:
        mode = im.mode
        pixels = np.asarray(im)
    Image.fromarray(change(pixels).astype(pixels.dtype).copy(), mode).save(path)


def shared_pattern(flags: list[str]) -> int:
    """Renders the -jitter request with one jitter pattern for all pixels and writes its PNGs."""
    sys.path.insert(0, str(REPO / "tools"))
    from jitter_defects import shared
    from raycheck.tracer.image import write_png
    from raycheck.tracer.scene.request import CourseCommand

    cmd = CourseCommand.from_argv(flags)
    for kind, image in shared(cmd.input, cmd.request).items():
        write_png(cmd.outputs[kind], image)
    return 0


def main(argv: list[str]) -> int:
    defect, flags = argv[0], argv[1:]
    if defect not in DEFECTS:
        print(f"corrupt.py: unknown defect {defect!r}", file=sys.stderr)
        return 2
    if defect == "sleep":
        time.sleep(60)
        return 0
    if defect == "segv":
        os.kill(os.getpid(), signal.SIGSEGV)
    if defect == "no_shadows":
        flags = without(flags, "-shadows", 0)
    elif defect == "no_normals":
        flags = without(flags, "-normals", 1)
    elif defect == "no_jitter":
        flags = without(flags, "-jitter", 0)
    elif defect == "samples4" and "-jitter" in flags:
        flags = flags + ["--samples", "4"]
    elif defect == "shared_pattern" and "-jitter" in flags:
        return shared_pattern(flags)
    elif defect == "double_size":
        i = flags.index("-size")
        flags = flags[:i + 1] + [str(2 * int(flags[i + 1])), str(2 * int(flags[i + 2]))] \
            + flags[i + 3:]

    import numpy as np
    from raycheck.tracer.cli import main as tracer_main

    code = tracer_main(flags)
    if code != 0:
        return code
    files = outputs(flags)
    if defect == "filter_2x" and "-filter" in flags:
        rewrite(files["color"], lambda p: np.minimum(p.astype(np.uint16) * 2, 255))
    elif defect == "flip":
        for path in files.values():
            rewrite(path, lambda p: p[::-1])
    elif defect == "truncate":
        data = files["color"].read_bytes()
        files["color"].write_bytes(data[:len(data) // 2])
    elif defect == "exit3":
        return 3
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
