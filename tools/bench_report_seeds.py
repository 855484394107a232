"""The report's false alarms measured (prints a table, never pass/fail): `raycheck report`
(the tracer against Mitsuba on every bundled case, the README's `make report` matrix without
its sweeps, stress and bench pages) run once per seed of the tracer's jittered images, each
failing case and image kind listed. The reference's realisations are the report's own
(distribution.REFERENCE_SEED + i): what varies is the candidate's draw, as it does between
a report's `--seed` values.

    .venv/bin/python tools/bench_report_seeds.py [--seeds 10] [--size 128] [-j N]
"""
from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from raycheck.harness.judge.verdict import ENGINES_JITTER_TEST


def report(seed: int, size: int, jobs: list[str], out: Path) -> dict | None:
    """report.json of the run; None (its message printed) where it could not run."""
    run = subprocess.run([sys.executable, "-m", "raycheck.harness", "report", "--seed",
                          str(seed), "--size", str(size), "--out", str(out), "--no-sweeps",
                          "--no-stress", "--no-bench", "--quiet", *jobs],
                         capture_output=True, text=True)
    if run.returncode not in (0, 1):  # 0: every case passed, 1: some failed
        print(run.stderr.strip(), file=sys.stderr)
        return None
    return json.loads((out / "report" / "report.json").read_text())


def positive(text: str) -> int:
    if not text.isdigit() or int(text) < 1:
        raise argparse.ArgumentTypeError(f"expected a whole number >= 1, found {text!r}")
    return int(text)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--seeds", type=positive, default=10, help="seeds 0..N-1 of the candidate")
    ap.add_argument("--size", type=positive, default=128)
    ap.add_argument("-j", "--jobs", type=positive, help="the report's -j")
    args = ap.parse_args()
    jobs = ["-j", str(args.jobs)] if args.jobs else []
    print(f"The report's false alarms: the tracer against Mitsuba, {args.size}x{args.size}, "
          f"jittered images at a false-alarm level of {ENGINES_JITTER_TEST.alpha:g} each")
    print(f"{'seed':>4} {'cases failed':>13} {'jittered images failed':>23}  failing")
    total_images = total_failed = 0
    start = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="raycheck-seeds-") as tmp:
        for seed in range(args.seeds):
            data = report(seed, args.size, jobs, Path(tmp) / str(seed))
            if data is None:
                return 2
            cases = data["cases"]
            failing = [f"{c['case']} {k['kind']}" for c in cases for k in c["kinds"]
                       if k["verdict"] != "pass"]
            jittered = [k for c in cases if c["jittered"] for k in c["kinds"]]
            failed_jittered = sum(k["verdict"] != "pass" for k in jittered)
            failed_cases = sum(c["verdict"] != "pass" for c in cases)
            total_images += len(jittered)
            total_failed += failed_jittered
            print(f"{seed:4} {failed_cases:>6}/{len(cases):<6} "
                  f"{failed_jittered:>11}/{len(jittered):<11}  {', '.join(failing) or '-'}",
                  flush=True)
    share = f"{total_failed / total_images:.2g}" if total_images else "no jittered image"
    print(f"all: {total_failed} of {total_images} jittered images failed "
          f"({share}; nominal at most {ENGINES_JITTER_TEST.alpha:g} "
          f"each); {time.perf_counter() - start:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
