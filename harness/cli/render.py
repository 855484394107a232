"""`raycheck render`: the tracer's command line (tracer/cli.py; `python -m raycheck.tracer`
alike)."""
from __future__ import annotations


def main(argv: list[str]) -> int:
    from raycheck.tracer.cli import main as tracer_main

    return tracer_main(argv, prog="raycheck render")
