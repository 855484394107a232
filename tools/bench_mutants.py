"""How well raycheck diagnoses mistakes nobody here chose: mutants of the student-filled
functions of the starter-shaped C++ solution (tests/solution_cpp/), made by a mutation tool
(universalmutator, the `mutants` extra), each built and checked by raycheck's check, and its
top explanation compared with the function the mutation is in.

    .venv/bin/python tools/bench_mutants.py [--sample held-out|tuning|all] [--limit N]
        [--seed S] [--functions F,...] [--size N] [--timeout S] [-j N] [--json FILE]
        [--markdown] [--solution DIR] [SCENE ...]
    .venv/bin/python tools/bench_mutants.py --from-json FILE [FILE ...] [--markdown] [--docs]

(--from-json: the tables of saved runs, e.g. one per sample, taken together; --docs writes
them into docs/findings.md and the README's findings section.)

Per mutant (the `mutate SOURCE --noCheck --showRules --lines LINES` of universalmutator, with
LINES the target functions' lines):
* file, line, function, operator (the universalmutator rule that made it, as its rule file
  writes it: `\\+ ==> -`), the original and the replacement line;
* held out or not: a mutant is in the held-out sample when the sha256 of its key
  `FILE|LINE|OPERATOR|REPLACEMENT` (UTF-8; FILE relative to the solution, `src/Light.cpp`; LINE
  1-based in the unmutated file; REPLACEMENT the mutated text with each line stripped of
  surrounding whitespace, lines joined by `\\n`), read as a hexadecimal number, is 0 mod 3.
  The held-out mutants are never looked at while tuning: tune on `--sample tuning`;
* built or not: only its translation unit is compiled (the command of the solution's
  compile_commands.json), linked with the solution's other objects (its link.txt); binaries
  and compile failures are cached by a sha256 of the mutant source, the compile and link
  commands and the solution's digest under $RAYCHECK_CACHE/mutants/. A binary identical to
  the solution's is an equivalent mutant by construction: not checked, not killed;
* killed or not: `raycheck check --strict` (through its Python API: CheckConfig, run_case,
  the same check.json entries; the unjittered cases first, their causes refuted by the
  cases the program passes, then the jittered ones with them as priors, as the check's
  runner does) on SCENES at a small size; killed where a case fails
  or errs.
  A mutant's check stops at its first timeout (the rest of its cases would time out too);
* its class, from the top finding of each failing image kind (a kind whose verdict is fail or
  error): `reproduced` (a cause, `cause:<code>` or `quirk:<code>`, whose reference with that
  mistake reproduces the image: "reproduces your image(s)", or for a jittered image "is a
  likely draw of the reference's distribution", and that names the mutated function), `right`
  (names the mutated function, without reproducing), `wrong` (names another function first,
  reproducing or not) or `nothing` (no function named: unexplained, a symptom finding, an
  error). A finding names a function by its catalogue entry (tracer/mistakes.py, a cause; a
  quirk's, tracer/quirks.py), else by a message starting with `Class::function:`; one that
  leaves several functions (a located finding's, a cause the images cannot tell from a
  mistake in another function) names none. The mutant's
  class is the most common class over its failing kinds, a tie going to the class of the
  earliest failing kind in the check's order (scenes in order, then cases, then color,
  normals, depth); its top explanation is that kind's top finding. reproduced + right +
  wrong + nothing = killed.

Prints a table per sample (the held-out one first: the headline), per function: mutants,
built, killed, reproduced, right function first, wrong first, nothing; totals; build and check
seconds per mutant; the date, machine, universalmutator version and the command. --markdown
prints them as the docs' tables. Exit status 0 (a benchmark: no target yet), 2 bad usage.
"""
from __future__ import annotations

import argparse
import fcntl
import hashlib
import json
import os
import random
import re
import shlex
import shutil
import subprocess
import sys
import tempfile
import time
from collections import Counter
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
SOLUTION = REPO / "tests" / "solution_cpp"
PROGRAM = "a2"

# the student-filled functions: the mutation targets, by file (relative to the solution)
TARGETS: dict[str, tuple[str, ...]] = {
    "src/Light.cpp": ("PointLight::getIllumination", "DirectionalLight::getIllumination"),
    "src/Material.cpp": ("Material::shade",),
    "src/Renderer.cpp": ("Renderer::traceRay", "Renderer::Render"),
    "src/Object3D.cpp": ("Sphere::intersect", "Plane::Plane", "Plane::intersect",
                         "Triangle::intersect", "Transform::intersect"),
}
FUNCTIONS = tuple(f for fs in TARGETS.values() for f in fs)
# the universalmutator rule files `mutate` uses for a .cpp file (genmutants.py: the universal
# rules, the language's, then c_like's), to name each mutant's rule by its text
RULE_FILES = ("universal.rules", "cpp.rules", "c_like.rules")

# The scenes every target function shows in, and the cases run on them. Each with why:
#   course/spheres_mirror    spheres on a plane, two point lights with falloff, Phong
#                            highlights, shadows and 4 mirror bounces (Sphere, Plane,
#                            PointLight, Material::shade, traceRay's shadows and mirrors)
#   features/shadows         a point and a directional light, both shadowed, one blocker beyond
#                            the point light (DirectionalLight, traceRay's shadow test)
#   features/transformed_plane  planes inside Transforms, one with normal (0,3,0): the raw
#                            normal and offset (Plane::Plane, Plane::intersect, Transform)
#   features/triangle        Triangle objects, both windings, one in a Transform
#   course/smooth_mesh       an OBJ mesh (octree) with interpolated normals, two directional
#                            lights and highlights (Triangle::intersect's normals)
#   course/ellipsoid         a sphere under a non-uniform scale and rotation over a plane:
#                            Transform's ray and normal transforms, shadows
#   features/inside_sphere   the camera inside a sphere (its far root), a point light with a
#                            blocker beyond it, a directional light
#   features/jitter_filter   thin triangles: -jitter and -filter (Renderer::Render's sampling)
SCENES = ("course/spheres_mirror", "features/shadows", "features/transformed_plane",
          "features/triangle", "course/smooth_mesh", "course/ellipsoid",
          "features/inside_sphere")
FEATURES = "plain,shadows,shadows+bounces"
AA_SCENES = ("features/jitter_filter",)
AA_FEATURES = "filter,jitter,jitter+filter"
SIZE = 48
TIMEOUT_S = 10.0
COMPILE_TIMEOUT_S = 180.0
CLASSES = ("reproduced", "right", "wrong", "nothing")
MESSAGE_CHARS = 200  # of a failing kind's top finding in the JSON, but for the mutant's top


# --- mutants ---------------------------------------------------------------------------------
@dataclass(frozen=True)
class Mutant:
    file: str  # relative to the solution: src/Light.cpp
    line: int  # 1-based, in the unmutated file
    function: str  # Class::name
    operator: str  # the universalmutator rule's text: \+ ==> -
    rule: str  # where the rule is: builtin:universal.rules:5 (universalmutator's numbering)
    original: str  # the unmutated line
    replacement: str  # the mutated text (a rule may add a line: `break;`)
    source: str = field(repr=False, compare=False, default="")  # the whole mutated file

    @property
    def key(self) -> str:
        return held_out_key(self.file, self.line, self.operator, self.replacement)

    @property
    def id(self) -> str:
        return f"{self.file}:{self.line}:{hashlib.sha256(self.key.encode()).hexdigest()[:8]}"

    @property
    def held_out(self) -> bool:
        return is_held_out(self.key)


def held_out_key(file: str, line: int, operator: str, replacement: str) -> str:
    """FILE|LINE|OPERATOR|REPLACEMENT, the replacement's lines stripped and joined by \\n."""
    text = "\n".join(part.strip() for part in replacement.strip("\n").split("\n"))
    return f"{file}|{line}|{operator}|{text}"


def is_held_out(key: str) -> bool:
    """One mutant in three, fixed for good: sha256(key) as a number, 0 mod 3."""
    return int(hashlib.sha256(key.encode("utf-8")).hexdigest(), 16) % 3 == 0


def _blanked(text: str) -> str:
    """The text with comments and string and character literals replaced by spaces (newlines
    kept): offsets and line numbers stay those of the text, braces in them do not count."""
    out = list(text)
    i, n = 0, len(text)
    while i < n:
        c = text[i]
        if text.startswith("//", i):
            j = text.find("\n", i)
            j = n if j < 0 else j
        elif text.startswith("/*", i):
            j = text.find("*/", i + 2)
            j = n if j < 0 else j + 2
        elif c in "\"'":
            j = i + 1
            while j < n and text[j] != c and text[j] != "\n":
                j += 2 if text[j] == "\\" else 1
            j = min(j + 1, n)
        else:
            i += 1
            continue
        for k in range(i, j):
            if out[k] != "\n":
                out[k] = " "
        i = j
    return "".join(out)


def _matching(code: str, start: int, open_: str, close: str) -> int:
    """The offset of the bracket closing the one at `start`."""
    depth = 0
    for i in range(start, len(code)):
        if code[i] == open_:
            depth += 1
        elif code[i] == close:
            depth -= 1
            if depth == 0:
                return i
    raise ValueError(f"no {close} closes the {open_} at offset {start}")


def function_lines(text: str, function: str) -> tuple[int, int]:
    """The first and last line (1-based) of a function's mutable text: from its body's first
    line (the line of the parameter list's `)` where code follows it there, as a constructor's
    initialiser list) to its closing brace. The definition is the line starting (unindented)
    with `<type> Class::name(` or `Class::name(`; ValueError where there is none."""
    code = _blanked(text)
    cls, name = function.split("::")
    match = re.search(rf"^(?!\s)[^\n;{{}}]*?\b{cls}::{name}\s*\(", code, re.MULTILINE)
    if match is None:
        raise ValueError(f"no definition of {function}")
    params_end = _matching(code, match.end() - 1, "(", ")")
    body = code.index("{", params_end)
    end = _matching(code, body, "{", "}")
    line_of = code.count
    after = code[params_end + 1:code.find("\n", params_end)]
    first = line_of("\n", 0, params_end) + 1
    if re.fullmatch(r"\s*(const)?\s*(override)?\s*\{?\s*", after):
        first += 1
    return first, line_of("\n", 0, end) + 1


def rule_texts() -> dict[str, str]:
    """universalmutator's rule id (builtin:universal.rules:5, as --showRules prints it) ->
    the rule's text, from the installed universalmutator's own rule parser."""
    from universalmutator.mutator import parseRules

    rules, _, _ = parseRules(list(RULE_FILES))
    return {source: text for _, (text, source) in rules}


def mutate_command() -> list[str]:
    """universalmutator's `mutate`: beside this Python (the venv's), else on PATH."""
    beside = Path(sys.executable).parent / "mutate"
    found = str(beside) if beside.exists() else shutil.which("mutate")
    if found is None:
        raise UsageError("universalmutator is not installed: pip install -e '.[mutants]'")
    return [found]


class UsageError(Exception):
    """Bad usage or a missing tool: one line on stderr, exit status 2."""


def generate(solution: Path = SOLUTION) -> list[Mutant]:
    """Every mutant universalmutator makes of the target functions' lines, in file and
    generation order, each program once (a rule that matches a line at several places can make
    the same program more than once)."""
    names = rule_texts()
    mutants: list[Mutant] = []
    made: set[str] = set()
    for rel, functions in TARGETS.items():
        path = solution / rel
        text = path.read_text(encoding="utf-8")
        original = text.splitlines(keepends=True)
        spans = {f: function_lines(text, f) for f in functions}
        lines = sorted({n for a, b in spans.values() for n in range(a, b + 1)})
        with tempfile.TemporaryDirectory(prefix="raycheck-mutate-") as tmp:
            line_file = Path(tmp) / "lines.txt"
            line_file.write_text("\n".join(map(str, lines)) + "\n")
            out = Path(tmp) / "mutants"
            proc = subprocess.run(
                [*mutate_command(), str(path.resolve()), "--noCheck", "--showRules",
                 "--lines", str(line_file), "--mutantDir", str(out)],
                cwd=tmp, capture_output=True, text=True, timeout=600)
            if proc.returncode != 0:
                raise RuntimeError(f"mutate {rel} failed: {proc.stdout[-2000:]}"
                                   f"{proc.stderr[-2000:]}")
            for chunk in proc.stdout.split("PROCESSING MUTANT: ")[1:]:
                head = re.match(r"(\d+):", chunk)
                written = re.search(r"\[written to (.+?)\]", chunk)
                rule = re.search(r"\(FROM: (.+?)\)\.\.\.", chunk)
                if head is None or written is None or rule is None:
                    continue  # redundant (a copy of the source): not written
                line = int(head[1])
                mutated = Path(written[1]).read_text(encoding="utf-8")
                if mutated in made:
                    continue
                made.add(mutated)
                new = mutated.splitlines(keepends=True)
                extra = len(new) - len(original)
                if new[:line - 1] != original[:line - 1] or \
                        new[line + extra:] != original[line:]:
                    raise RuntimeError(f"{written[1]}: not a change of line {line} alone")
                function = next(f for f, (a, b) in spans.items() if a <= line <= b)
                mutants.append(Mutant(rel, line, function, names.get(rule[1], rule[1]),
                                      rule[1], original[line - 1].rstrip("\n"),
                                      "".join(new[line - 1:line + extra]).rstrip("\n"),
                                      mutated))
    return mutants


def select(mutants: list[Mutant], sample: str, functions: set[str] | None,
           limit: int | None, seed: int) -> list[Mutant]:
    """The mutants of a sample (held-out, tuning or all) and functions; with limit, a seeded
    random subset of them, in their order."""
    chosen = [m for m in mutants if (sample == "all" or m.held_out == (sample == "held-out"))
              and (functions is None or m.function in functions)]
    if limit is not None and limit < len(chosen):
        keep = set(random.Random(seed).sample(range(len(chosen)), limit))
        chosen = [m for i, m in enumerate(chosen) if i in keep]
    return chosen


# --- builds ----------------------------------------------------------------------------------
def mutants_cache() -> Path:
    from raycheck.tracer.cache import cache_folder

    return cache_folder() / "mutants"


def _tool_version(tool: str) -> str:
    try:
        return subprocess.run([tool, "--version"], capture_output=True, text=True,
                              timeout=30).stdout.splitlines()[0]
    except (OSError, IndexError, subprocess.SubprocessError):
        return "missing"


def solution_digest(solution: Path) -> str:
    """sha256 of what a build of the solution reads (CMakeLists.txt, src/, vecmath/), of its
    place (its compile commands name it) and of the cmake and compiler versions."""
    h = hashlib.sha256(str(solution.resolve()).encode() + b"\0")
    files = [solution / "CMakeLists.txt", *sorted(p for d in ("src", "vecmath")
                                                  for p in (solution / d).rglob("*")
                                                  if p.is_file())]
    for p in files:
        h.update(p.relative_to(solution).as_posix().encode() + b"\0" + p.read_bytes() + b"\0")
    h.update(_tool_version("cmake").encode() + _tool_version("c++").encode())
    return h.hexdigest()


@dataclass(frozen=True)
class BaseBuild:
    """The solution built once: per translation unit its compile command, and the link."""

    folder: str
    digest: str
    compile: dict[str, tuple[str, tuple[str, ...], str]]  # src/Light.cpp -> (cwd, argv, file)
    objects: dict[str, str]  # src/Light.cpp -> its object as the link command names it
    link: tuple[str, ...]  # argv, run in folder
    binary_sha256: str
    seconds: float
    cached: bool


def build_base(solution: Path = SOLUTION, jobs: int = 2) -> BaseBuild:
    """Configure and build the solution once per digest (cached: a second call reads it)."""
    for tool in ("cmake", "c++"):
        if shutil.which(tool) is None:
            raise UsageError(f"{tool} is not installed (a C++ toolchain and cmake are needed)")
    digest = solution_digest(solution)
    folder = mutants_cache() / "base" / digest[:24]
    folder.parent.mkdir(parents=True, exist_ok=True)
    start = time.perf_counter()
    cached = True
    with open(folder.parent / f"{digest[:24]}.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)  # one process builds; the others wait, then read
        if not (folder / "built").exists():
            cached = False
            shutil.rmtree(folder, ignore_errors=True)
            for argv in (["cmake", "-S", str(solution.resolve()), "-B", str(folder),
                          "-G", "Unix Makefiles", "-DCMAKE_BUILD_TYPE=Release",
                          "-DCMAKE_EXPORT_COMPILE_COMMANDS=ON"],
                         ["cmake", "--build", str(folder), "-j", str(jobs)]):
                proc = subprocess.run(argv, capture_output=True, text=True, timeout=900)
                if proc.returncode != 0:
                    raise UsageError(f"the solution does not build ({' '.join(argv[:2])}): "
                                     f"{_first_error(proc.stdout + proc.stderr)}")
            (folder / "built").write_text(digest)
    entries = json.loads((folder / "compile_commands.json").read_text())
    link = tuple(shlex.split((folder / "CMakeFiles" / f"{PROGRAM}.dir" / "link.txt")
                             .read_text()))
    compile_: dict[str, tuple[str, tuple[str, ...], str]] = {}
    objects: dict[str, str] = {}
    root = solution.resolve()
    for e in entries:
        rel = Path(e["file"]).resolve().relative_to(root).as_posix()
        command = (tuple(e["arguments"]) if "arguments" in e
                   else tuple(shlex.split(e["command"])))
        compile_[rel] = (e["directory"], command, e["file"])
        out = command[command.index("-o") + 1]
        objects[rel] = next(a for a in link if a == out or a.endswith("/" + out)
                            or out.endswith("/" + a))
    binary = (folder / PROGRAM).read_bytes()
    return BaseBuild(str(folder), digest, compile_, objects, link,
                     hashlib.sha256(binary).hexdigest(), time.perf_counter() - start, cached)


@dataclass
class Built:
    status: str  # built, identical (built, byte for byte the solution's), failed
    binary: str | None
    seconds: float
    cached: bool
    error: str = ""  # the compiler's first error


def _first_error(log: str) -> str:
    for line in log.splitlines():
        if re.search(r"\berror\b", line):
            return line.strip()[:300]
    return log.strip().splitlines()[-1][:300] if log.strip() else ""


def _compile_argv(base: BaseBuild, rel: str, source: Path, obj: Path) -> list[str]:
    """The TU's compile command for another source file and object (no dependency file)."""
    _, argv, file = base.compile[rel]
    out: list[str] = []
    args = iter(argv)
    for a in args:
        if a in ("-MT", "-MF", "-MQ", "-o"):
            next(args, None)  # and its value
        elif a not in ("-MD", "-MMD", "-c", file):
            out.append(a)
    return [*out, "-o", str(obj), "-c", str(source)]


def build_mutant(base: BaseBuild, mutant: Mutant) -> Built:
    """The mutant's program: its TU compiled alone, linked with the solution's other objects;
    cached by the mutant source, the commands and the solution's digest."""
    start = time.perf_counter()
    h = hashlib.sha256()
    for part in (base.digest, mutant.file, " ".join(base.compile[mutant.file][1]),
                 " ".join(base.link), mutant.source):
        h.update(part.encode() + b"\0")
    key = h.hexdigest()
    folder = mutants_cache() / "bin" / key[:2]
    binary, failed = folder / key, folder / f"{key}.failed"
    if binary.exists():
        status = "identical" if _sha256(binary) == base.binary_sha256 else "built"
        return Built(status, str(binary), time.perf_counter() - start, True)
    if failed.exists():
        return Built("failed", None, time.perf_counter() - start, True,
                     failed.read_text(encoding="utf-8"))
    folder.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(prefix="raycheck-mutant-") as tmp:
        # the same file name: the object's symbols (and so an equivalent mutant's binary)
        # are those of the solution's
        source = Path(tmp) / Path(mutant.file).name
        source.write_text(mutant.source, encoding="utf-8")
        obj, exe = Path(tmp) / "mutant.o", Path(tmp) / PROGRAM
        link = [str(obj) if a == base.objects[mutant.file] else a for a in base.link]
        link[link.index("-o") + 1] = str(exe)
        error = None
        for argv, cwd in ((_compile_argv(base, mutant.file, source, obj),
                           base.compile[mutant.file][0]), (link, base.folder)):
            try:
                proc = subprocess.run(argv, cwd=cwd, capture_output=True, text=True,
                                      timeout=COMPILE_TIMEOUT_S)
            except subprocess.TimeoutExpired:  # not cached: a busy machine's, maybe
                return Built("failed", None, time.perf_counter() - start, False,
                             f"{argv[0]} ran past {COMPILE_TIMEOUT_S:g} s")
            if proc.returncode != 0:
                error = _first_error(proc.stdout + proc.stderr).replace(str(source),
                                                                         mutant.file)
                break
        if error is not None:
            _write_atomic(failed, error.encode())
            return Built("failed", None, time.perf_counter() - start, False, error)
        _write_atomic(binary, exe.read_bytes(), executable=True)
    status = "identical" if _sha256(binary) == base.binary_sha256 else "built"
    return Built(status, str(binary), time.perf_counter() - start, False)


def _sha256(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def _write_atomic(path: Path, data: bytes, executable: bool = False) -> None:
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=".tmp", suffix=".part")
    with os.fdopen(fd, "wb") as f:
        f.write(data)
    if executable:
        os.chmod(tmp, 0o755)
    os.replace(tmp, path)


# --- checks and classes ----------------------------------------------------------------------
@dataclass(frozen=True)
class Plan:
    """What a mutant is checked on: (scenes, features) parts, at one size."""

    parts: tuple[tuple[tuple[str, ...], str], ...]
    size: int
    timeout: float

    def describe(self) -> list[str]:
        return [f"{', '.join(scenes)} ({features})" for scenes, features in self.parts]


def function_named(code: str, message: str, functions: tuple[str, ...] = ()) -> str | None:
    """The starter-code function a finding names: a cause's catalogue entry, a quirk's, else
    a message starting with Class::function:; None for none (unexplained, a symptom) and
    for a finding that leaves several `functions` (a located one's; a cause the images
    cannot tell from a mistake in another function)."""
    from raycheck.tracer.mistakes import MISTAKES
    from raycheck.tracer.quirks import BY_CODE

    if len(functions) > 1:
        return None
    if code.startswith("cause:"):
        mistake = MISTAKES.get(code.removeprefix("cause:"))
        return mistake.function if mistake is not None else None
    if code.startswith("quirk:"):
        quirk = BY_CODE.get(code.removeprefix("quirk:"))
        return quirk.function if quirk is not None else None
    match = re.match(r"\s*([A-Za-z_]\w*::~?[A-Za-z_]\w*):", message)
    return match[1] if match else None


def reproduces(code: str, message: str) -> bool:
    """Whether a cause's (or quirk's) reference with the mistake reproduces the image: within
    the check's tolerance, every kind of the case (causes.py: "reproduces your images"; a
    quirk's: "reproduces your image"), or for a jittered image by the statistical test
    (jitter_causes.py: "is a likely draw of the reference's distribution"). A cause that only
    "matches N% of the pixels where your images differ" does not."""
    if not (code.startswith("cause:") or code.startswith("quirk:")) or \
            code == "cause:unexplained":
        return False
    return "reproduces your image" in message or \
        "is a likely draw of the reference's distribution" in message


def kind_class(function: str, code: str, message: str, functions: tuple[str, ...] = ()) -> str:
    named = function_named(code, message, functions)
    if named is None:
        return "nothing"
    if named != function:
        return "wrong"
    return "reproduced" if reproduces(code, message) else "right"


def mutant_class(function: str, failing: list[dict]) -> tuple[str | None, dict | None]:
    """The mutant's class over its failing kinds (in the check's order) and the kind whose top
    finding is its top explanation: the most common class, a tie to the earliest kind's."""
    if not failing:
        return None, None
    counts = Counter(k["class"] for k in failing)
    most = max(counts.values())
    first = next(k for k in failing if counts[k["class"]] == most)
    return first["class"], first


def check_binary(binary: str, plan: Plan, function: str) -> dict:
    """raycheck's check of a program on the plan's cases (--strict), as `raycheck check` runs
    them (the unjittered cases first, their causes tried on the cases the program passes
    and the failing cases whose cause one refutes run again without it, then the jittered
    cases with the causes as priors): every kind's verdict, the failing kinds' top findings
    and classes."""
    from raycheck.harness.commands.check import check_entries
    from raycheck.harness.commands.check_config import CheckConfig
    from raycheck.harness.diagnosis.refute import refutations
    from raycheck.harness.pipeline.case import CaseResult, run_case
    from raycheck.harness.pipeline.matrix import (
        Job,
        case_record,
        first_waves,
        matrix_jobs,
        narrowed_result,
        narrowed_round,
        program_priors,
        refuting_rounds,
    )

    jobs = []
    for scenes, features in plan.parts:
        config = CheckConfig(renderer=shlex.quote(binary), scenes=tuple(map(Path, scenes)),
                             size=(plan.size, plan.size), features=features,
                             timeout=plan.timeout, strict=True)
        jobs += matrix_jobs(config.matrix())[0]
    timed_out = False

    def run(phase: list[Job]) -> list[CaseResult]:
        nonlocal timed_out
        out = []
        for job in phase:
            result = run_case(job.case, job.candidate, job.reference, job.settings,
                              job.priors, job.refuting)
            out.append(result)
            timed_out = result.error is not None and result.error.code == "timeout"
            if timed_out:
                break
        return out

    first = [j for j in jobs if not j.case.jittered]
    results = first_waves(first, run, case_record)
    if not timed_out:
        refuter = refuting_rounds(first, results, run,
                                  lambda trials: [refutations(t) for t in trials],
                                  Job.ran_result)
        later = program_priors(first, [case_record(r) for r in results],
                               [replace(j, refuting=refuter.of(j.program))
                                for j in jobs if j.case.jittered])
        results += run(later)
        results = narrowed_round((first + later)[:len(results)], results, case_record,
                                 narrowed_result)
    kinds, failing = 0, []
    for entry in check_entries([case_record(r) for r in results]):
        kinds += 1
        if entry.verdict == "pass":
            continue
        top = entry.findings[0] if entry.findings else None
        code, message = (top.code, top.message) if top else ("-", "")
        functions = tuple(top.functions or ()) if top else ()
        failing.append({"case": f"{entry.scene}/{entry.feature}", "kind": entry.kind,
                        "verdict": str(entry.verdict), "code": code,
                        "message": message, "function": function_named(code, message, functions),
                        "reproduces": reproduces(code, message),
                        "class": kind_class(function, code, message, functions)})
    skipped = len(jobs) - len(results)
    return {"kinds": kinds, "failing": failing, "cases_not_run": skipped}


def run_mutant(base: BaseBuild, mutant: Mutant, plan: Plan, threads: int | None) -> dict:
    """One mutant, built and checked (in a worker process): its JSON row."""
    from raycheck.harness.pipeline.executor import use_threads

    use_threads(threads)
    row: dict = {"id": mutant.id, **{k: v for k, v in asdict(mutant).items() if k != "source"},
                 "key": mutant.key, "held_out": mutant.held_out}
    built = build_mutant(base, mutant)
    row["build"] = {"status": built.status, "seconds": round(built.seconds, 3),
                    "cached": built.cached, "error": built.error}
    row["built"] = built.status != "failed"
    row.update(killed=False, check_seconds=None, kinds=0, failing=[], cases_not_run=0,
               **{"class": None}, top=None)
    if built.status != "built":  # failed, or the solution's own binary: nothing to check
        return row
    start = time.perf_counter()
    checked = check_binary(built.binary or "", plan, mutant.function)
    row["check_seconds"] = round(time.perf_counter() - start, 3)
    cls, top = mutant_class(mutant.function, checked["failing"])
    # the top explanation's message whole, the other kinds' shortened (a mutant can fail 40)
    failing = [k if k is top else {**k, "message": k["message"][:MESSAGE_CHARS]}
               for k in checked["failing"]]
    row.update(killed=bool(failing), kinds=checked["kinds"], failing=failing,
               cases_not_run=checked["cases_not_run"], top=top, **{"class": cls})
    return row


# --- tables ----------------------------------------------------------------------------------
COLUMNS = ("mutants", "built", "killed", "reproduced", "right", "wrong", "nothing")
HEADERS = ("function", "mutants", "built", "killed", "reproduced", "right function first",
           "wrong first", "nothing", "not killed")


def table_rows(rows: list[dict]) -> list[tuple[str, dict[str, int]]]:
    """Per function (in TARGETS' order, those with mutants) and in all: the counts."""
    out = []
    for function in [*FUNCTIONS, "all"]:
        mine = [r for r in rows if function in ("all", r["function"])]
        if not mine and function != "all":
            continue
        c = {"mutants": len(mine), "built": sum(r["built"] for r in mine),
             "identical": sum(r["build"]["status"] == "identical" for r in mine),
             "killed": sum(r["killed"] for r in mine)}
        c.update({k: sum(r["class"] == k for r in mine) for k in CLASSES})
        c["not killed"] = c["built"] - c["killed"]
        out.append((function, c))
    return out


def _pct(n: int, of: int) -> str:
    return f"{n} ({n / of:.0%})" if of else str(n)


def format_table(rows: list[dict], markdown: bool) -> str:
    body = []
    for function, c in table_rows(rows):
        name = f"`{function}`" if markdown and function != "all" else \
            ("**all**" if markdown else function)
        body.append([name, str(c["mutants"]), _pct(c["built"], c["mutants"]),
                     _pct(c["killed"], c["built"]),
                     *(_pct(c[k], c["killed"]) for k in CLASSES), _pct(c["not killed"],
                                                                      c["built"])])
    if markdown:
        return "\n".join(["| " + " | ".join(HEADERS) + " |",
                          "|" + "---|" * len(HEADERS)] +
                         ["| " + " | ".join(r) + " |" for r in body])
    widths = [max(len(h), *(len(r[i]) for r in body)) for i, h in enumerate(HEADERS)]
    fmt = "  ".join(f"{{:<{w}}}" if i == 0 else f"{{:>{w}}}" for i, w in enumerate(widths))
    return "\n".join([fmt.format(*HEADERS)] + [fmt.format(*r) for r in body])


def summary_lines(rows: list[dict]) -> list[str]:
    """Shares and seconds of a sample, in words."""
    _, c = table_rows(rows)[-1]
    built = [r for r in rows if r["built"]]
    fresh = [r["build"]["seconds"] for r in rows if not r["build"]["cached"]]
    checked = [r["check_seconds"] for r in rows if r["check_seconds"] is not None]
    erred = sum(1 for r in rows if r["killed"] and
                all(k["verdict"] == "error" for k in r["failing"]))
    n = c["mutants"]
    lines = [f"{n} mutant{'s' if n != 1 else ''}: {_pct(n - c['built'], n)} not built "
             f"(universalmutator's --noCheck leaves non-compiling ones); of {c['built']} "
             f"built, {c['identical']} identical to the solution's binary (equivalent), "
             f"{c['not killed'] - c['identical']} more passing every case (equivalent or "
             f"invisible on these scenes), {c['killed']} killed"
             + (f", {erred} of them only by errors (crash, timeout: nothing specific)"
                if erred else "") + "."]
    mimics = sum(1 for r in rows if r["class"] == "wrong" and r["top"]["reproduces"])
    if mimics:
        lines.append(f"Of the {c['wrong']} wrong, {mimics} reproduced the images with a "
                     "mistake of another function: these scenes cannot tell the two apart.")
    if built or fresh:
        lines.append("build: " + (f"{sum(fresh) / len(fresh):.2f} s a mutant compiled and "
                                  f"linked ({len(fresh)})" if fresh else "all cached")
                     + "; check: " + (f"{sum(checked) / len(checked):.1f} s a mutant "
                                      f"({len(checked)} checked; killed "
                                      f"{_mean(rows, True):.1f} s, not killed "
                                      f"{_mean(rows, False):.1f} s)" if checked else "none"))
    return lines


def _mean(rows: list[dict], killed: bool) -> float:
    s = [r["check_seconds"] for r in rows
         if r["check_seconds"] is not None and r["killed"] == killed]
    return sum(s) / len(s) if s else 0.0


def machine() -> dict:
    from raycheck.harness.provenance import provenance

    prov = provenance()
    return {"cpu": prov["cpu"], "cores": os.cpu_count() or 1, "git commit": prov["git commit"],
            "raycheck": prov["raycheck"], "platform": prov["platform"],
            "compiler": _tool_version("c++"), "cmake": _tool_version("cmake")}


def merged(runs: list[dict]) -> dict:
    """Runs of the same solution and plan (e.g. one per sample) as one: their mutants
    together, their seconds added, their commands listed."""
    first = runs[0]
    for run in runs[1:]:
        for key in ("solution_digest", "size", "timeout", "scenes", "universalmutator"):
            if run[key] != first[key]:
                raise UsageError(f"the runs differ in {key}: {first[key]} and {run[key]}")
    keys = [{m["key"] for m in run["mutants"]} for run in runs]
    if sum(map(len, keys)) != len(set().union(*keys)):
        raise UsageError("the runs share mutants")
    return {**first, "date": max(run["date"] for run in runs),
            "command": "`; `".join(run["command"] for run in runs),
            "seconds": sum(run["seconds"] for run in runs),
            "mutants": [m for run in runs for m in unique(run["mutants"])]}


def unique(rows: list[dict]) -> list[dict]:
    """Each mutant once: the rows of a run made before generate() dropped repeated programs
    hold a mutant once per time the tool made it, under one key."""
    seen: set[str] = set()
    out = []
    for r in rows:
        if r["key"] not in seen:
            seen.add(r["key"])
            out.append(r)
    return out


def provenance_line(data: dict) -> str:
    m = data["machine"]
    return (f"Measured {data['date']} at commit {m['git commit'][:7]} by `{data['command']}` "
            f"(universalmutator {data['universalmutator']}; {data['seconds']:.0f} s on "
            f"{m['cores']} cores, "
            f"{m['cpu']}; {data['size']}x{data['size']}, --strict, timeout "
            f"{data['timeout']:g} s; scenes: {'; '.join(data['scenes'])}).")


def write_docs(data: dict) -> None:
    """The tables of a run in docs/findings.md (both samples) and the README (the held-out
    one), between their <!-- mutants:begin --> and <!-- mutants:end --> lines."""
    held_out = [r for r in data["mutants"] if r["held_out"]]
    _, c = table_rows(held_out)[-1]
    m = data["machine"]
    short = "\n".join([format_table(held_out, True), "",
                       f"The held-out sample: {c['mutants']} mutants, {c['built']} built, "
                       f"{c['killed']} killed; measured {data['date']} at commit "
                       f"{m['git commit'][:7]} on {m['cores']} cores ({m['cpu']}), "
                       f"universalmutator {data['universalmutator']}."])
    for path, body in ((REPO / "docs" / "findings.md", report(data, True)),
                       (REPO / "README.md", short)):
        text = path.read_text(encoding="utf-8")
        begin, end = "<!-- mutants:begin -->", "<!-- mutants:end -->"
        if begin not in text or end not in text:
            raise UsageError(f"{path.name} has no {begin} ... {end} block")
        head, _, rest = text.partition(begin)
        _, _, tail = rest.partition(end)
        path.write_text(f"{head}{begin}\n{body}\n{end}{tail}", encoding="utf-8")


def report(data: dict, markdown: bool) -> str:
    rows = data["mutants"]
    out = []
    for sample, title in (("held-out", "held-out sample (the headline)"),
                          ("tuning", "tuning sample")):
        mine = [r for r in rows if r["held_out"] == (sample == "held-out")]
        if not mine:
            continue
        out.append(f"{'### ' if markdown else ''}{title}: {len(mine)} "
                   f"mutant{'s' if len(mine) != 1 else ''}\n")
        out.append(format_table(mine, markdown))
        out.append("")
        out.extend(summary_lines(mine))
        out.append("")
    out.append(provenance_line(data) + " Classes: reproduced + right + wrong + nothing = "
               "killed (the module's docstring).")
    return "\n".join(out)


def main(argv: list[str]) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("scenes", nargs="*",
                    help=f"scenes (default: {', '.join(SCENES)} in {FEATURES}, and "
                         f"{', '.join(AA_SCENES)} in {AA_FEATURES})")
    ap.add_argument("--features", help=f"features of the given scenes (default {FEATURES})")
    ap.add_argument("--sample", choices=("held-out", "tuning", "all"), default="all",
                    help="which mutants (default all; while tuning: tuning)")
    ap.add_argument("--functions", help=f"comma-separated, of {', '.join(FUNCTIONS)}")
    ap.add_argument("--limit", type=int, metavar="N", help="a seeded random N of them")
    ap.add_argument("--seed", type=int, default=0, metavar="S", help="for --limit (default 0)")
    ap.add_argument("--size", type=int, default=SIZE, help=f"square image size ({SIZE})")
    ap.add_argument("--timeout", type=float, default=TIMEOUT_S, metavar="S",
                    help=f"seconds a render of a mutant may take (default {TIMEOUT_S:g})")
    ap.add_argument("-j", "--jobs", type=int, default=None, metavar="N",
                    help="mutants at once, in worker processes (default: the number of "
                         "cores; 1: in this process)")
    ap.add_argument("--json", type=Path, metavar="FILE", help="also write every mutant's row")
    ap.add_argument("--markdown", action="store_true", help="the tables in the docs' format")
    ap.add_argument("--solution", type=Path, default=SOLUTION, metavar="DIR",
                    help="the C++ solution (default tests/solution_cpp)")
    ap.add_argument("--from-json", type=Path, nargs="+", metavar="FILE",
                    help="no run: print the tables of --json runs' FILEs (taken together: "
                         "e.g. one run per sample)")
    ap.add_argument("--docs", action="store_true",
                    help="with --from-json: write the tables into docs/findings.md and the "
                         "README")
    args = ap.parse_args(argv)
    if args.docs and not args.from_json:
        ap.error("--docs needs --from-json")
    if args.from_json:
        try:
            data = merged([json.loads(f.read_text(encoding="utf-8")) for f in args.from_json])
            if args.docs:
                write_docs(data)
        except (OSError, ValueError, KeyError, UsageError) as e:
            print(f"bench_mutants: {e}", file=sys.stderr)
            return 2
        print(report(data, args.markdown))
        return 0
    functions = set(args.functions.split(",")) if args.functions else None
    if functions and functions - set(FUNCTIONS):
        ap.error(f"--functions: unknown {', '.join(sorted(functions - set(FUNCTIONS)))}")
    if args.jobs is not None and args.jobs < 1:
        ap.error(f"-j {args.jobs}: at least 1")
    if args.limit is not None and args.limit < 1:
        ap.error(f"--limit {args.limit}: at least 1")
    if args.size < 4 or args.timeout <= 0:
        ap.error("--size: at least 4; --timeout: more than 0")
    parts = (((tuple(args.scenes), args.features or FEATURES),) if args.scenes else
             ((SCENES, args.features or FEATURES), (AA_SCENES, AA_FEATURES)))
    plan = Plan(parts, args.size, args.timeout)
    from importlib.metadata import PackageNotFoundError, version

    from raycheck.harness.pipeline.executor import workers
    try:
        try:
            um_version = version("universalmutator")
        except PackageNotFoundError:
            raise UsageError("universalmutator is not installed: "
                             "pip install -e '.[mutants]'") from None
        start = time.perf_counter()
        base = build_base(args.solution, args.jobs or os.cpu_count() or 1)
        mutants = select(generate(args.solution), args.sample, functions, args.limit,
                         args.seed)
    except UsageError as e:
        print(f"bench_mutants: {e}", file=sys.stderr)
        return 2
    print(f"{len(mutants)} mutants ({args.sample}"
          + (f", {args.limit} seeded by {args.seed}" if args.limit else "") + "); solution "
          + ("built before" if base.cached else f"built in {base.seconds:.0f} s"),
          file=sys.stderr, flush=True)
    rows = []
    with workers(args.jobs) as w:
        futures = [w.executor.submit(run_mutant, base, m, plan, w.threads) for m in mutants]
        for i, future in enumerate(futures, 1):
            row = future.result()
            rows.append(row)
            top = row["top"]
            said = (row["build"]["status"] if row["build"]["status"] != "built" else
                    f"{row['class']}: {top['code']} ({top['case']} {top['kind']})" if top
                    else "not killed")
            print(f"[{i}/{len(mutants)}] {row['id']} {row['function']} "
                  f"{row['operator']!r}: {said}", file=sys.stderr, flush=True)
    data = {"date": time.strftime("%Y-%m-%d"), "command": _command(argv),
            "machine": machine(), "universalmutator": um_version, "size": args.size,
            "timeout": args.timeout, "scenes": plan.describe(), "sample": args.sample,
            "limit": args.limit, "seed": args.seed, "solution_digest": base.digest,
            "seconds": time.perf_counter() - start, "mutants": rows}
    print(report(data, args.markdown))
    if args.json:
        args.json.write_text(json.dumps(data, indent=1), encoding="utf-8")
    return 0


def _command(argv: list[str]) -> str:
    return shlex.join([".venv/bin/python", "tools/bench_mutants.py", *argv])


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
