"""Rewrites docs/performance.md's generated tables and README.md's short one from one saved
`raycheck bench` run.

    python tools/bench_readme.py BENCH.json [FILE ...]   (default: docs/performance.md README.md)

BENCH.json: what `raycheck bench --throughput --versus CMD --json BENCH.json` wrote (this does
what `raycheck bench ... --readme docs/performance.md --readme README.md` does at the end of its
run). Only the parts between a file's <!-- bench:begin --> and <!-- bench:end --> (or
<!-- bench-short:begin --> and <!-- bench-short:end -->) change. Exit status 2 with
one line on stderr for a missing or unreadable file, data without every table, or a file
without the markers.
"""
from __future__ import annotations

import json
import sys
from pathlib import Path

from raycheck.harness.bench.records import BenchRun
from raycheck.harness.pages.benchpage import (
    ReadmeError,
    generated_spans,
    readme_block,
    write_readme,
)

USAGE = "usage: python tools/bench_readme.py BENCH.json [FILE ...]"
DEFAULT_FILES = ("docs/performance.md", "README.md")


def main(argv: list[str]) -> int:
    if argv[:1] in (["-h"], ["--help"]):
        print(__doc__.strip())
        return 0
    if not argv:
        print(USAGE, file=sys.stderr)
        return 2
    bench, readmes = Path(argv[0]), [Path(f) for f in argv[1:] or DEFAULT_FILES]
    try:
        try:
            data = BenchRun.from_json(json.loads(bench.read_text(encoding="utf-8")))
            readme_block(data)  # the data first
        except (ValueError, OSError) as e:  # JSONDecodeError, ReadmeError, UnicodeDecodeError
            raise ReadmeError(getattr(e, "strerror", None) or str(e)) from None
    except ReadmeError as e:
        print(f"bench_readme: {bench}: {e}", file=sys.stderr)
        return 2
    try:
        for readme in readmes:  # every file checked before any is written
            generated_spans(readme.read_text(encoding="utf-8"))
        for readme in readmes:
            write_readme(readme, data)
            print(f"tables rewritten: {readme}")
    except (ReadmeError, OSError, UnicodeDecodeError) as e:
        print(f"bench_readme: {readme}: {getattr(e, 'strerror', None) or e}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
