"""`python -m raycheck.harness`: the raycheck command."""
import sys

from .cli import main

sys.exit(main(ending=True))
