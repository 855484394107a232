"""`counting.py --log=LOG <course flags>`: the reference tracer (`python -m raycheck.tracer`, in
this process), appending one line per invocation to LOG first, so that tests can count renders.
(An option, not a bare path: the harness identifies a program by the last file argument.)"""
from __future__ import annotations

import sys


def main(argv: list[str]) -> int:
    log, flags = argv[0].removeprefix("--log="), argv[1:]
    with open(log, "a", encoding="utf-8") as f:  # one short appended line: atomic on Linux
        f.write(" ".join(flags) + "\n")
    from raycheck.tracer.cli import main as tracer_main

    return tracer_main(flags)


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
