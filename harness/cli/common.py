"""What every harness command line shares: argparse with one-line errors, option types that
refuse bad values before any work, and the exit-status contract (0 success, 1 a check failed,
2 bad usage or input, 130 interrupted), with no traceback for any expected failure."""
from __future__ import annotations

import argparse
import os
import sys
from contextlib import contextmanager
from importlib.metadata import version
from pathlib import Path
from typing import TYPE_CHECKING, Callable, Iterator

from raycheck.tracer.process import EXIT_USAGE
from raycheck.tracer.scene.errors import printable

if TYPE_CHECKING:
    from ..pipeline.matrix import Runner



class UsageError(ValueError):
    """Bad usage or input found by a command itself (one-line message)."""


class Parser(argparse.ArgumentParser):
    """argparse whose usage errors are one line on stderr and exit status 2."""

    def error(self, message: str):  # noqa: D401 - argparse's hook
        print(printable(f"{self.prog}: error: {message} (see {self.prog} --help)"),
              file=sys.stderr)
        sys.exit(EXIT_USAGE)


def parser(prog: str, description: str, epilog: str | None = None) -> Parser:
    ap = Parser(prog=prog, description=description, epilog=epilog,
                formatter_class=argparse.RawDescriptionHelpFormatter, allow_abbrev=False)
    ap.add_argument("--version", action="version", version=f"raycheck {version('raycheck')}")
    return ap


def positive_int(text: str) -> int:
    if not (text.isascii() and text.isdigit()) or int(text) < 1:
        raise argparse.ArgumentTypeError(f"expected a positive integer, found {text!r}")
    return int(text)


def unsigned_int(limit: int) -> Callable[[str], int]:
    def parse(text: str) -> int:
        if not (text.isascii() and text.isdigit()) or int(text) > limit:
            raise argparse.ArgumentTypeError(f"expected an integer in 0..{limit}, found {text!r}")
        return int(text)

    parse.__name__ = "integer"
    return parse


def at_least_4(text: str) -> int:
    """A count of realisations: the test's leave-one-out variance needs at least 4."""
    if not (text.isascii() and text.isdigit()) or not 4 <= int(text) <= 4096:
        raise argparse.ArgumentTypeError(f"expected an integer in 4..4096, found {text!r}")
    return int(text)


def positive_float(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        value = float("nan")
    if not value > 0 or value == float("inf"):
        raise argparse.ArgumentTypeError(f"expected a positive number, found {text!r}")
    return value


def out_folder(text: str) -> Path:
    """A folder to write into: it may not exist yet, but must not be a file, and its parent
    must be a folder."""
    if not text:
        raise argparse.ArgumentTypeError("expected a folder name, found ''")
    path = Path(text)
    if path.exists() and not path.is_dir():
        raise argparse.ArgumentTypeError(f"{text} exists and is not a folder")
    parent = path.resolve().parent
    if not path.exists() and not parent.is_dir():
        raise argparse.ArgumentTypeError(f"the folder {parent} does not exist")
    return path


def out_file(text: str) -> Path:
    """A file to write: its folder must exist, and it must not be a folder."""
    path = Path(text)
    if not text or path.is_dir():
        raise argparse.ArgumentTypeError(f"{text!r} is not a file name")
    if not path.resolve().parent.is_dir():
        raise argparse.ArgumentTypeError(f"the folder of {text} does not exist")
    return path


def add_budget_options(ap: argparse.ArgumentParser) -> None:
    from raycheck.tracer.scene.limits import DEFAULT_MAX_KERNEL_TESTS, DEFAULT_MAX_RAYS

    ap.add_argument("--max-memory", metavar="SIZE", type=memory_size, default=None,
                    help="refuse renders estimated to need more memory (default 8G)")
    ap.add_argument("--max-rays", metavar="N", type=positive_int, default=DEFAULT_MAX_RAYS,
                    help="refuse renders casting more rays (default 2^36)")
    ap.add_argument("--max-kernel-tests", metavar="N", type=positive_int,
                    default=DEFAULT_MAX_KERNEL_TESTS,
                    help="refuse scenes whose kernel would hold more sphere and plane tests "
                         "(default 1024; compile time grows with their square)")


def memory_size(text: str) -> int:
    from raycheck.tracer.scene.limits import parse_bytes

    try:
        return parse_bytes(text)
    except ValueError as e:
        raise argparse.ArgumentTypeError(str(e)) from None


def budget_of(args: argparse.Namespace):
    from raycheck.tracer.scene.limits import DEFAULT_MAX_MEMORY, Budget

    return Budget(args.max_memory or DEFAULT_MAX_MEMORY, args.max_rays, args.max_kernel_tests)


def run(prog: str, action: Callable[[], int]) -> int:
    """Runs a command's action under the course command line's contract (process.run_command):
    expected failures end in one line on stderr and exit status 2, Ctrl-C in 130, SIGTERM in
    143."""
    from concurrent.futures import BrokenExecutor

    from raycheck.tracer.process import run_command
    from raycheck.tracer.render_limits import LimitError
    from raycheck.tracer.scene import SceneError
    from raycheck.tracer.scene.flags import FlagError

    from ..check_options import ConfigError
    from ..pipeline.executor import SchedulerError
    from ..renderers import RenderError

    # BrokenExecutor: a worker process died (killed, out of memory); the finished cases are
    # in the result cache for --resume
    return run_command(prog, action, (UsageError, ConfigError, SceneError, FlagError,
                                      LimitError, RenderError, SchedulerError, BrokenExecutor))


def add_case_size_option(ap: argparse.ArgumentParser) -> None:
    """--size W H of check and grade: one image size for every case."""
    ap.add_argument("--size", type=positive_int, nargs=2, metavar=("W", "H"),
                    help="image size of every case (default: a scene's own # size, else "
                         "128 128)")


def add_run_options(ap: argparse.ArgumentParser) -> None:
    """-j, --scheduler and --resume: where the cases run and whether finished ones count."""
    ap.add_argument("-j", "--jobs", type=positive_int, metavar="N",
                    help="run N cases at once in local worker processes (default: "
                         "$RAYCHECK_JOBS, else the number of cores; 1: in this process)")
    ap.add_argument("--scheduler", metavar="ADDRESS",
                    help="run the cases on the workers of a Dask cluster (tcp://HOST:8786)")
    ap.add_argument("--resume", action="store_true",
                    help="reuse the results of an earlier (or interrupted) run into the same "
                         "folder where the candidate, scene and request are unchanged")


def add_sandbox_options(ap: argparse.ArgumentParser, default: str) -> None:
    """--sandbox and --sandbox-read: how candidate programs run (renderers/sandbox.py)."""
    from ..renderers.sandbox import SandboxMode

    ap.add_argument("--sandbox", type=SandboxMode, default=SandboxMode(default),
                    choices=list(SandboxMode), metavar="MODE",
                    help="run each candidate program (and each build) in a bubblewrap "
                         "sandbox: no network, no files but its own folder and the system's, "
                         "its own processes; auto: where bubblewrap runs, else with a "
                         f"warning; required: or an error; off (default: {default})")
    ap.add_argument("--sandbox-read", action="append", type=Path, default=[], metavar="DIR",
                    help="a folder the sandboxed program may read (a runtime it needs "
                         "outside /usr); repeatable")


@contextmanager
def case_runner(args: argparse.Namespace, out: Path) -> Iterator[Runner]:
    """The Runner of -j/--scheduler/--resume for output folder `out`, its result cache
    beside it (results.cache_folder)."""
    from ..pipeline.executor import workers
    from ..pipeline.matrix import Runner
    from ..storage.results import ResultCache, cache_folder

    if args.jobs is not None and args.scheduler is not None:
        raise UsageError("-j and --scheduler exclude each other")
    jobs = args.jobs
    if jobs is None and os.environ.get("RAYCHECK_JOBS"):
        try:
            jobs = positive_int(os.environ["RAYCHECK_JOBS"])
        except argparse.ArgumentTypeError as e:
            raise UsageError(f"RAYCHECK_JOBS: {e}") from None
    with workers(jobs, args.scheduler) as w:
        yield Runner(w, ResultCache(cache_folder(out) / "results"), args.resume, args.quiet)
