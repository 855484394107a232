"""`raycheck export`: a course scene as Mitsuba XML (mitsuba_ref/export.py)."""
from __future__ import annotations


def main(argv: list[str]) -> int:
    from raycheck.mitsuba_ref.export import main_export

    return main_export(argv, prog="raycheck export")
