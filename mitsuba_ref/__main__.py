"""`python -m raycheck.mitsuba_ref`: the Mitsuba reference's command line (cli.py)."""
import sys

from raycheck.tracer.process import interruptible


def _main() -> int:
    from .cli import main

    return main()


sys.exit(interruptible("python -m raycheck.mitsuba_ref", _main, ending=True))
