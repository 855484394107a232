"""`raycheck reference`: the Mitsuba reference's command line (mitsuba_ref/cli.py)."""
from __future__ import annotations


def main(argv: list[str]) -> int:
    from raycheck.mitsuba_ref.cli import main as reference_main

    return reference_main(argv, prog="raycheck reference")
