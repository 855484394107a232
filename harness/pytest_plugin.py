"""pytest plugin: `raycheck check` as pytest tests, so a course can put the check into its CI.

    pytest --raycheck-renderer "python3 my_tracer.py" [--raycheck-reference tracer|mitsuba]
           [--raycheck-results DIR] [--raycheck-scenes SCENE ...] [--raycheck-size W H]
           [--raycheck-features LIST] [--raycheck-timeout S] [--junitxml FILE]

Installed with raycheck (entry point pytest11 `raycheck`), so this works in any folder, with
or without test files of its own; where plugin autoloading is off, add `-p raycheck`. The
options mean what `raycheck check`'s do; each has an ini key of its own name with underscores
(raycheck_renderer, raycheck_results, ...; paths relative to the ini file), the command
line winning. Without a renderer the plugin adds no tests and changes nothing.

One test per case and image kind, named scene/feature/kind (course/arch/shadows/color) under
the node `raycheck` (`-k shadows` selects as usual). The kinds of a case share one render of
candidate and reference. With a results folder each case's pictures and page go there as it
runs, and at the end index.html and check.json as `raycheck check` writes them.

pytest imports this module in every run wherever raycheck is installed, so it imports nothing
of the harness: the check (pytest_check.py) is imported only where a renderer is named.
"""
from __future__ import annotations

from pathlib import Path
from typing import Any, Literal

import pytest

from .check_options import DEFAULT_TIMEOUT_S, FEATURES_HELP

IniType = Literal["string", "paths", "args", "linelist", "float"]  # pytest's addini types used here
# option name -> (add_option keyword arguments, ini type)
OPTIONS: dict[str, tuple[dict[str, Any], IniType]] = {
    "renderer": ({"metavar": "CMD", "help": "check this course renderer: a command taking the "
                  "course's flags (\"python3 my_tracer.py\"), or tracer / mitsuba"}, "string"),
    "reference": ({"metavar": "NAME", "help": "judge it against tracer (default) or "
                   "mitsuba"}, "string"),
    "results": ({"type": Path, "metavar": "DIR", "help": "write each case's pictures and page, "
                 "index.html and check.json there"}, "string"),
    "scenes": ({"type": Path, "nargs": "+", "metavar": "SCENE", "help": "scene files (default: "
                "every bundled course and feature scene)"}, "paths"),
    "size": ({"type": int, "nargs": 2, "metavar": ("W", "H"), "help": "image size of every "
              "case (default: a scene's own, else 128 128)"}, "args"),
    "features": ({"metavar": "LIST", "help": f"comma-separated features (of "
                  f"{FEATURES_HELP}; default: all)"}, "string"),
    "timeout": ({"type": float, "metavar": "S", "help": f"wall-clock limit per render "
                 f"(default {DEFAULT_TIMEOUT_S:g} s)"}, "float"),
}


def pytest_addoption(parser: pytest.Parser) -> None:
    group = parser.getgroup("raycheck", "raycheck: check a course ray tracer against the "
                                        "reference")
    for name, (kwargs, ini_type) in OPTIONS.items():
        group.addoption(f"--raycheck-{name}", dest=f"raycheck_{name}", default=None, **kwargs)
        parser.addini(f"raycheck_{name}", f"default of --raycheck-{name}"
                      + (" (relative to the ini file)" if name in ("results", "scenes")
                         else ""), type=ini_type, default=None)


def pytest_configure(config: pytest.Config) -> None:
    """Registers the run only where a renderer is named, so that otherwise nothing changes."""
    settings = {name: setting(config, name) for name in OPTIONS}
    if settings["renderer"] is not None:
        from .pytest_check import register

        register(config, settings)


def setting(config: pytest.Config, name: str) -> Any:
    """The command line's value, else the ini file's; None where neither sets it."""
    value = config.getoption(f"raycheck_{name}")
    if value is None:
        value = config.getini(f"raycheck_{name}")
    return None if value in ("", []) else value
