"""A course renderer that never finishes and leaves a child behind: `orphan.py PIDFILE <course
flags>` starts a child Python that sleeps (PIDFILE in its argv, as a marker to find it by),
writes "its own pid, the child's pid" to PIDFILE, then sleeps itself. A harness that kills only
the program it started leaves the child running."""
from __future__ import annotations

import os
import subprocess
import sys
import time
from pathlib import Path


def main(argv: list[str]) -> int:
    pidfile = Path(argv[0])
    child = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(120)", str(pidfile)])
    pidfile.write_text(f"{os.getpid()} {child.pid}\n")
    time.sleep(120)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
