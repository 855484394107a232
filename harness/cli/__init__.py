"""The `raycheck` command: one entry point, one module per command (harness/cli/<name>.py,
each with `main(argv) -> int`). Exit status everywhere: 0 success, 1 a check failed, 2 bad
usage or input, 130 interrupted, 143 terminated (tracer/process.py)."""
from __future__ import annotations

import importlib
import os
import sys

from raycheck.tracer.process import EXIT_OK, EXIT_USAGE, interruptible, raise_swallowed

# name -> one-line summary, in the order `raycheck help` lists them
COMMANDS = {
    "render": "render a scene with raycheck's tracer (the course program's flags)",
    "reference": "render the same with Mitsuba 3",
    "check": "run any course renderer on every case and judge it against the reference",
    "grade": "check every submission of a class; a class table and grades.csv",
    "autograder": "a Gradescope autograder folder that grades one submission",
    "compare": "one case, tracer and Mitsuba, with metrics, maps and an HTML page",
    "report": "the comparison suite, tracer against Mitsuba, as an HTML report",
    "info": "what a scene uses and which flags can change its image",
    "export": "a scene as a Mitsuba XML file",
    "gallery": "render the bundled course scenes with the tracer",
    "bench": "render times of the course scenes; BVH throughput",
    "stress": "the extreme scenes in every mode against the float64 robust render",
}


def usage() -> str:
    width = max(map(len, COMMANDS))
    lines = "\n".join(f"  {name:<{width}}  {text}" for name, text in COMMANDS.items())
    return (f"usage: raycheck COMMAND [ARGS ...]\n\ncommands:\n{lines}\n\n"
            "raycheck COMMAND --help tells more; raycheck --version prints the version.")


def main(argv: list[str] | None = None, *, ending: bool = False) -> int:
    """The command's exit status; ending: the process ends after it (process.interruptible)."""
    argv = sys.argv[1:] if argv is None else list(argv)
    prog = f"raycheck {argv[0]}" if argv and argv[0] in COMMANDS else "raycheck"
    # an interrupt while a command's modules load, or its flags are read, ends it as one while
    # it works does (there the command's own run_command answers it)
    return interruptible(prog, lambda: dispatch(argv), ending=ending)


def dispatch(argv: list[str]) -> int:
    if not argv:
        print(usage(), file=sys.stderr)
        return EXIT_USAGE
    cmd, rest = argv[0], argv[1:]
    if cmd in ("-h", "--help"):
        print(usage())
        return EXIT_OK
    if cmd == "--version":
        # imported here: importlib.metadata (email, zipfile, csv ...) is most of the
        # harness's start-up, and `raycheck render` must start as fast as the tracer
        from importlib.metadata import version

        print(f"raycheck {version('raycheck')}")
        return EXIT_OK
    if cmd == "help":
        if not rest:
            print(usage())
            return EXIT_OK
        cmd, rest = rest[0], ["--help"]
    if cmd not in COMMANDS:
        print(f"raycheck: error: unknown command '{cmd}' (commands: {', '.join(COMMANDS)}; "
              "see raycheck --help)", file=sys.stderr)
        return EXIT_USAGE
    module = importlib.import_module(f"{__name__}.{cmd}")
    raise_swallowed()
    try:
        return module.main(rest)
    except SystemExit as e:  # argparse's --help, --version and usage errors
        return e.code if isinstance(e.code, int) else EXIT_USAGE
    except BrokenPipeError:  # the reader went away (`raycheck help | head`): nothing to say
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return EXIT_OK


def entry() -> int:
    """The `raycheck` console script; a process that only renders (`raycheck render`) starts
    and ends as `python -m raycheck.tracer` does (tracer.kernel.backend)."""
    if sys.argv[1:2] != ["render"]:
        return main(ending=True)
    from raycheck.tracer.kernel.backend import begin_render_process, end_render_process

    begin_render_process()
    end_render_process(main(ending=True))


if __name__ == "__main__":
    sys.exit(entry())
