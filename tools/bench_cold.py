"""Where a new user's first check goes: one check of RENDERER on the bundled scenes from an
empty HOME (no Dr.Jit kernel cache, no raycheck cache), then the same check again in that HOME
(warm), each in a fresh process, with its time split by what the cases spent it on.

    .venv/bin/python tools/bench_cold.py --renderer /path/to/a2 [-j 2] [--scenes ...]
                                          [--json FILE]
    .venv/bin/python tools/bench_cold.py --tests [-j 2]     (the quick test suite instead)

Columns: wall-clock seconds of the whole command; per role, the seconds its renders took summed
over the cases (the workers run cases side by side, so the sums can exceed the wall clock):
the candidate's runs, the reference's renders (kernels traced and compiled on first use), the
jittered cases' realisations of the reference; and the distinct kernels Dr.Jit compiled into
HOME (its cache's entries after the run). The rest of the wall clock is start-up, imports,
findings and pages. The warm run finds the reference's renders and distributions in raycheck's
cache: a cached render reports the time it took when it was made, a cached distribution 0."""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROLES = ("candidate", "reference", "mean")


def child(renderer: str, jobs: int, scenes: list[str], out: Path) -> dict:
    """One check in this process (HOME set by the parent); its numbers."""
    from raycheck.harness.commands.check_config import CheckConfig
    from raycheck.harness.pipeline.executor import workers
    from raycheck.harness.pipeline.matrix import Runner, run_matrix
    from raycheck.harness.provenance import provenance
    from raycheck.harness.records import Role

    start = time.perf_counter()
    matrix = CheckConfig(renderer=renderer, scenes=tuple(Path(s) for s in scenes)).matrix()
    with workers(jobs) as w:
        rows, _, _ = run_matrix(matrix, out, provenance(), runner=Runner(w, quiet=True))
    wall = time.perf_counter() - start
    sums = {r: sum((row.times.get(Role(r)) or {}).get("cold_s") or 0.0 for row in rows)
            for r in ROLES}
    kernels = Path.home() / ".drjit"
    return {"wall_s": wall, "cases": len(rows), "role_s": sums,
            "kernels": sum(1 for p in kernels.rglob("*") if p.is_file())
            if kernels.is_dir() else 0}


def tests(jobs: int, env: dict[str, str]) -> int:
    """The quick test suite as `make test` runs it, from the empty HOME, then again in it:
    wall clock and the kernels compiled into HOME."""
    repo = Path(__file__).resolve().parent.parent
    times = {}
    for run in ("cold", "warm"):
        start = time.perf_counter()
        done = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider",
                               "--numprocesses", str(jobs), "--dist", "loadfile"],
                              cwd=repo, env={k: v for k, v in env.items()
                                             if k != "PYTHONDONTWRITEBYTECODE"},
                              capture_output=True, text=True)
        times[run] = time.perf_counter() - start
        if done.returncode != 0:
            print(done.stdout[-3000:], file=sys.stderr)
            return 1
        kernels = Path(env["HOME"]) / ".drjit"
        count = sum(1 for p in kernels.rglob("*") if p.is_file()) if kernels.is_dir() else 0
        print(f"quick suite {run}: {times[run]:7.1f} s ({done.stdout.strip().splitlines()[-1]}; "
              f"{count} kernels in the Dr.Jit cache)")
    print(f"cold/warm: {times['cold'] / times['warm']:.2f} (-n {jobs}, {os.cpu_count()} cores)")
    return 0


def main(argv: list[str]) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--renderer", help="the candidate's command")
    ap.add_argument("--tests", action="store_true",
                    help="time the quick test suite cold and warm instead of a check")
    ap.add_argument("-j", "--jobs", type=int, default=os.cpu_count() or 1)
    ap.add_argument("--scenes", nargs="*", default=[])
    ap.add_argument("--json", type=Path, help="also write the numbers here")
    ap.add_argument("--child", type=Path, help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if (args.renderer is None) == (not args.tests):
        ap.error("give --renderer CMD (a check) or --tests (the quick test suite)")
    if args.child is not None:
        print(json.dumps(child(args.renderer, args.jobs, args.scenes, args.child)))
        return 0
    results = {}
    with tempfile.TemporaryDirectory(prefix="raycheck-cold-") as tmp:
        home = Path(tmp) / "home"
        home.mkdir()
        env = {k: v for k, v in os.environ.items()
               if not k.startswith(("RAYCHECK_", "DRJIT_CACHE", "PYTEST_"))} | \
            {"HOME": str(home)}
        if args.tests:
            return tests(args.jobs, env)
        for run in ("cold", "warm"):
            start = time.perf_counter()
            done = subprocess.run([sys.executable, __file__, "--renderer", args.renderer,
                                   "-j", str(args.jobs), "--scenes", *args.scenes,
                                   "--child", str(Path(tmp) / run)],
                                  env=env, capture_output=True, text=True)
            if done.returncode != 0:
                print(done.stderr[-3000:], file=sys.stderr)
                return 1
            results[run] = json.loads(done.stdout.strip().splitlines()[-1])
            results[run]["process_s"] = time.perf_counter() - start
    cold, warm = results["cold"], results["warm"]
    print(f"{'':<34} {'cold':>9} {'warm':>9} {'cold/warm':>9}")
    rows = [("the command, wall clock (s)", "process_s"),
            ("candidate's runs, summed (s)", ("role_s", "candidate")),
            ("reference's renders, summed (s)", ("role_s", "reference")),
            ("realisations, summed (s)", ("role_s", "mean"))]
    for label, key in rows:
        c, w = ((cold[key], warm[key]) if isinstance(key, str)
                else (cold[key[0]][key[1]], warm[key[0]][key[1]]))
        print(f"{label:<34} {c:9.1f} {w:9.1f} {c / w if w else float('nan'):9.2f}")
    print(f"{'kernels in the Dr.Jit cache':<34} {cold['kernels']:9d} {warm['kernels']:9d}")
    print(f"({cold['cases']} cases, -j {args.jobs}, {os.cpu_count()} cores; warm: the "
          "reference's renders come from raycheck's cache with the time they took when made)")
    if args.json is not None:
        args.json.write_text(json.dumps(results, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
