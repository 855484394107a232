"""Rewrites docs/performance.md's generated tables from one saved `raycheck bench` run.

    python tools/bench_readme.py BENCH.json [docs/performance.md]

BENCH.json: what `raycheck bench --throughput --versus CMD --json BENCH.json` wrote (this does
what `raycheck bench ... --readme docs/performance.md` does at the end of its run). Only
the part between the file's <!-- bench:begin --> and <!-- bench:end --> changes. Exit status 2 with
one line on stderr for a missing or unreadable file, data without every table, or a file
without the markers.
"""
from __future__ import annotations

import json
import sys
from pathlib import Path

from raycheck.harness.pages.benchpage import ReadmeError, readme_block, write_readme

USAGE = "usage: python tools/bench_readme.py BENCH.json [docs/performance.md]"


def main(argv: list[str]) -> int:
    if argv[:1] in (["-h"], ["--help"]):
        print(__doc__.strip())
        return 0
    if not 1 <= len(argv) <= 2:
        print(USAGE, file=sys.stderr)
        return 2
    bench, readme = Path(argv[0]), Path(argv[1] if len(argv) == 2 else "docs/performance.md")
    try:
        try:
            data = json.loads(bench.read_text(encoding="utf-8"))
            readme_block(data if isinstance(data, dict) else {})  # the data first
        except (ValueError, OSError) as e:  # JSONDecodeError, ReadmeError, UnicodeDecodeError
            raise ReadmeError(getattr(e, "strerror", None) or str(e)) from None
    except ReadmeError as e:
        print(f"bench_readme: {bench}: {e}", file=sys.stderr)
        return 2
    try:
        write_readme(readme, data)
    except (ReadmeError, OSError, UnicodeDecodeError) as e:
        print(f"bench_readme: {readme}: {getattr(e, 'strerror', None) or e}", file=sys.stderr)
        return 2
    print(f"tables rewritten: {readme}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
