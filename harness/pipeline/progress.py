"""Progress of a long run: on a terminal one line redrawn in place (count, rate, ETA, the last
case), with failures kept above it; elsewhere (logs, CI) one plain line per finished case, with
the time so far and an estimate of the time left."""
from __future__ import annotations

import sys
import time
from typing import TextIO


def _duration(seconds: float) -> str:
    seconds = int(round(seconds))
    return f"{seconds // 60}m{seconds % 60:02d}s" if seconds >= 60 else f"{seconds}s"


class Progress:
    def __init__(self, total: int, stream: TextIO | None = None, quiet: bool = False) -> None:
        self.total = total
        self.stream = stream or sys.stdout
        self.quiet = quiet
        self.tty = self.stream.isatty()
        self.done = 0
        self.start = time.perf_counter()

    def step(self, text: str, failed: bool = False) -> None:
        """One more item finished; `text` says which and how it went."""
        self.done += 1
        if self.quiet:
            return
        elapsed = time.perf_counter() - self.start
        rate = self.done / elapsed if elapsed > 0 else 0.0
        eta = (self.total - self.done) / rate if rate > 0 else 0.0
        count = f"[{self.done}/{self.total}]"
        if not self.tty:
            left = f", about {_duration(eta)} left" if self.done < self.total else ""
            print(f"{count} {text} ({elapsed:.0f} s{left})", file=self.stream, flush=True)
            return
        if failed:  # kept: a line of its own above the bar
            print(f"\r\033[K{count} {text}", file=self.stream)
        bar = (f"{count} {self.done / max(self.total, 1):4.0%} {rate:.1f}/s "
               f"ETA {_duration(eta)}  {text}")
        end = "\n" if self.done == self.total else ""
        print(f"\r\033[K{bar[:160]}", end=end, file=self.stream, flush=True)
