"""`holding.py --log=LOG --gate=FILE <course flags>`: counting.py's reference tracer, except
that an invocation whose flags differ from the first one logged waits (up to a minute) for FILE
to exist: a run's first case completes, and its next case waits until the test lets it go, so
that the test can act while the run is certainly in the middle."""
from __future__ import annotations

import sys
import time
from pathlib import Path

from counting import main as counting_main

WAIT_S = 60.0


def main(argv: list[str]) -> int:
    log, gate = argv[0].removeprefix("--log="), Path(argv[1].removeprefix("--gate="))
    flags = " ".join(argv[2:])
    earlier = Path(log).read_text(encoding="utf-8").splitlines() if Path(log).exists() else []
    if earlier and earlier[0] != flags:
        deadline = time.monotonic() + WAIT_S
        while not gate.exists() and time.monotonic() < deadline:
            time.sleep(0.05)
    return counting_main([argv[0], *argv[2:]])


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
