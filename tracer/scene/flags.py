"""The course program's command line (spec §10): single-dash flags in any order, later repeats
override. Extra options of ours are double-dash and listed by the caller."""
from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path

from .errors import quote
from .lexer import FLOAT_RE, INT_RE, MAX_INT_DIGITS
from .limits import (
    DEFAULT_MAX_KERNEL_TESTS,
    DEFAULT_MAX_MEMORY,
    DEFAULT_MAX_RAYS,
    Budget,
    parse_bytes,
)
from .outputs import float_file
from .request import RenderRequest


class FlagError(ValueError):
    """A bad command line; the message names the flag and the problem."""


COURSE_FLAGS_HELP = """course flags (spec §10; in any order, a later repeat overrides):
  -input scene.txt        the scene (required)
  -output a.png           the color image (.png, or .exr for the float values)
  -normals n.png          the normals image, (n+1)/2 per channel
  -depth min max d.png    the depth image, (t-min)/(max-min), gray
  -size w h               image size (default 100 100)
  -bounces n              mirror recursion depth (default 0)
  -shadows                hard shadows
  -jitter                 16 jittered samples per pixel
  -filter                 3x3 supersampling with the 1-2-1 filter"""


def wants_help(argv: list[str]) -> bool:
    """-h or --help anywhere on a command line (not as the value of a flag)."""
    return any(a in ("-h", "--help") for a in argv)


def help_text(prog: str, summary: str, options: dict[str, str]) -> str:
    """A course-flag command's --help: usage, what it does, the course flags and its own
    double-dash options (name -> description)."""
    width = max((len(k) for k in options), default=0)
    ours = "\n".join(f"  {name:<{max(width, 22)}}  {text}" for name, text in options.items())
    return (f"usage: {prog} -input scene.txt [course flags] [options]\n\n{summary}\n\n"
            f"{COURSE_FLAGS_HELP}\n\noptions:\n{ours}\n\nExit status: 0 success, 2 bad "
            "usage or input (one line on stderr, no output file touched).")


FLAG_ARITY = {"-input": 1, "-output": 1, "-normals": 1, "-depth": 3, "-size": 2, "-bounces": 1,
          "-shadows": 0, "-jitter": 0, "-filter": 0}


def _int(flag: str, text: str, lo: int) -> int:
    if INT_RE.fullmatch(text) and len(text.lstrip("+-").lstrip("0")) > MAX_INT_DIGITS:
        raise FlagError(f"{flag}: expected an integer of at most {MAX_INT_DIGITS} digits, "
                        f"found {quote(text)}")
    if not INT_RE.fullmatch(text) or int(text) < lo:
        raise FlagError(f"{flag}: expected an integer >= {lo}, found {quote(text)}")
    return int(text)


@dataclass
class CourseCommand:
    """A parsed course command line: the request, the scene file, the files to write (kind ->
    path) and our double-dash options."""

    request: RenderRequest
    input: Path | None
    outputs: dict[str, Path] = field(default_factory=dict)
    extra: dict[str, str | bool | list[str]] = field(default_factory=dict)


def request_from_argv(argv: list[str]) -> RenderRequest:
    """The request of a course command line (--samples and --seed included); -input may be
    left out here."""
    return parse_course_flags(argv, {"samples": str, "seed": str},
                              require_input=False).request


def _float(flag: str, text: str) -> float:
    """A C float (the course reads flags with atof/strtof): words like nan or inf are refused;
    a value beyond float32's range is kept as written here and becomes ±inf in float32."""
    if not FLOAT_RE.fullmatch(text):
        raise FlagError(f"{flag}: expected a number, found {quote(text)}")
    return float(text)


MAX_SEED = 2**64 - 1


def parse_course_flags(argv: list[str], extra: dict[str, type] | None = None,
                       require_input: bool = True) -> CourseCommand:
    """Parse course flags plus double-dash extras given as {name: bool | str | list} (a list
    option may be given more than once: its values in order). Where the caller takes
    --samples and --seed, they go into the request (checked here)."""
    extra = extra or {}
    given: dict[str, str | bool | list[str]] = {}
    req: dict = {}
    inputs: Path | None = None
    outputs: dict[str, Path] = {}
    i = 0
    while i < len(argv):
        flag = argv[i]
        if flag.startswith("--"):
            name, eq, value = flag[2:].partition("=")
            if name not in extra:
                known = ", ".join(f"--{k}" for k in extra) or "none"
                raise FlagError(f"unknown option {quote(flag)} (options: {known})")
            if extra[name] is bool:
                if eq:
                    raise FlagError(f"--{name} takes no value")
                given[name] = True
                i += 1
                continue
            if not eq:
                if i + 1 >= len(argv):
                    raise FlagError(f"--{name} needs a value")
                value = argv[i + 1]
                i += 1
            if extra[name] is list:
                listed = given.setdefault(name, [])
                assert isinstance(listed, list)
                listed.append(value)
            else:
                given[name] = value
            i += 1
            continue
        if flag not in FLAG_ARITY:
            raise FlagError(f"unknown flag {quote(flag)} (flags: {' '.join(FLAG_ARITY)})")
        n = FLAG_ARITY[flag]
        vals = argv[i + 1:i + 1 + n]
        if len(vals) < n or any(v in FLAG_ARITY for v in vals):
            raise FlagError(f"{flag} needs {n} argument{'s' if n > 1 else ''}")
        i += 1 + n
        if flag == "-input":
            inputs = Path(vals[0])
        elif flag == "-output":
            outputs["color"] = Path(vals[0])
        elif flag == "-normals":
            outputs["normals"] = Path(vals[0])
        elif flag == "-depth":
            req["depth_min"] = _float(flag, vals[0])
            req["depth_max"] = _float(flag, vals[1])
            outputs["depth"] = Path(vals[2])
        elif flag == "-size":
            req["width"] = _int(flag, vals[0], 1)
            req["height"] = _int(flag, vals[1], 1)
        elif flag == "-bounces":
            req["bounces"] = _int(flag, vals[0], 0)
        else:
            req[flag[1:]] = True
    if inputs is None and require_input:
        raise FlagError("-input scene.txt is required")
    if "seed" in given:
        req["seed"] = unsigned_option("seed", str(given["seed"]), "a non-negative integer",
                                      MAX_SEED)
    if "samples" in given:  # its range is a render limit (limits.request_problem)
        req["samples"] = unsigned_option("samples", str(given["samples"]), "a positive integer",
                                         2**32 - 1)
    request = RenderRequest(**req, kinds=tuple(outputs) or ("color",))
    return CourseCommand(request, inputs, outputs, given)


_DIGITS = re.compile(r"[0-9]{1,19}")  # ASCII digits only: str.isdigit() accepts '²' and '٣'


def unsigned_option(option: str, text: str, what: str, limit: int) -> int:
    """The value of --option as an integer in 0..limit, or a FlagError naming it."""
    if not _DIGITS.fullmatch(text) or int(text) > limit:
        raise FlagError(f"--{option}: expected {what} up to {limit}, found {quote(text)}")
    return int(text)


def budget_from_args(cmd: CourseCommand) -> Budget:
    """The budget of --max-memory SIZE, --max-rays N and --max-kernel-tests N (defaults
    otherwise)."""
    memory, rays = cmd.extra.get("max-memory"), cmd.extra.get("max-rays")
    tests = cmd.extra.get("max-kernel-tests")
    try:
        memory_bytes = parse_bytes(str(memory)) if memory is not None else DEFAULT_MAX_MEMORY
    except ValueError as e:
        raise FlagError(f"--max-memory: {e}") from None
    ray_count = DEFAULT_MAX_RAYS if rays is None else \
        unsigned_option("max-rays", str(rays), "a number of rays", 2**63)
    kernel_tests = DEFAULT_MAX_KERNEL_TESTS if tests is None else \
        unsigned_option("max-kernel-tests", str(tests), "a number of tests", 2**31)
    return Budget(memory_bytes, ray_count, kernel_tests)


def check_output_path(path: Path, *suffixes: str) -> None:
    """An output file can be written: one of the suffixes, an existing folder, not a folder."""
    if path.suffix.lower() not in suffixes:
        raise FlagError(f"output file names must end in {' or '.join(suffixes)}, found "
                        f"{quote(str(path), None)}")
    folder = path.parent if str(path.parent) else Path(".")
    if not folder.is_dir():
        raise FlagError(f"folder of output file {quote(str(path), None)} does not exist")
    if path.is_dir():
        raise FlagError(f"output file {quote(str(path), None)} is a folder")


def check_outputs(cmd: CourseCommand) -> None:
    """At least one image is named, and each can be written as a PNG or an OpenEXR file; with
    --float also its values beside it (outputs.float_file), each image's file of its own."""
    if not cmd.outputs:
        raise FlagError("nothing to write: give -output, -normals or -depth")
    for path in cmd.outputs.values():
        check_output_path(path, ".png", ".exr")
    if cmd.extra.get("float"):
        written: dict[Path, str] = {}
        for kind, path in cmd.outputs.items():
            values = float_file(path)
            check_output_path(values, ".npy")
            other = written.setdefault(values.resolve(), kind)
            if other != kind:
                raise FlagError(f"--float: the {other} and {kind} images' values would both "
                                f"be written to {quote(str(values), None)}")
