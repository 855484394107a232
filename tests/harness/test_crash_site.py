"""Where a compiled program crashed (harness/diagnosis/crash_site.py): gdb's backtraces, as the
script of CommandRenderer.backtrace prints them, read into the student function to look at;
and the check of the real C++ solution with a crash written into it, in the sandbox too.

The logs below are gdb 13's output for the C++ solution (tests/solution_cpp/, built Release)
with the crash the test's name says, on course/spheres_mirror; the two without the C
library's debugging information were printed with gdb's debug-file-directory emptied."""
from __future__ import annotations

import shutil
from pathlib import Path

import pytest
from solution import Edit, build_solution, copy_solution
from test_check import MESH, MIRROR, REPO, SHADOWS, run_check

from raycheck.harness.diagnosis.crash_site import (
    Frame,
    crash_site,
    located,
    parse_backtrace,
    parse_memcheck,
    stuck,
)
from raycheck.harness.renderers import Debugger
from raycheck.harness.renderers.sandbox import unavailable_reason
from raycheck.tracer.scene.request import RenderRequest

FPE = """$1 = 8
$2 = (void *) 0x555555565ec8 <Renderer::Render()+1960>
$3 = (void *) 0x7fffffffd3f0
#0  0x0000555555565ec8 in Renderer::Render() ()
#1  0x00005555555590a6 in main ()
#0  0x0000555555565ec8 in Renderer::Render() ()
#1  0x00005555555590a6 in main ()
"""
_KILL = "(threadid=..., signo=..., no_tid=...) at ./nptl/pthread_kill.c"
HEAP = f"""$1 = 6
$2 = (void *) 0x1f40
$3 = (void *) 0x7fffffffd160
#0  __pthread_kill_implementation {_KILL}:44
#1  0x00007ffff7aa8f4f in __pthread_kill_internal {_KILL}:78
#2  0x00007ffff7a59fb2 in __GI_raise (sig=...) at ../sysdeps/posix/raise.c:26
#3  0x00007ffff7a44472 in __GI_abort () at ./stdlib/abort.c:79
#4  0x00007ffff7a9d42f in __libc_message (action=..., fmt=...) at ../sysdeps/posix/libc_fatal.c:156
#5  0x00007ffff7ab286a in malloc_printerr (str=...) at ./malloc/malloc.c:5662
#6  0x00007ffff7ab2a2c in munmap_chunk (p=...) at ./malloc/malloc.c:3054
#7  0x00007ffff7ab6fa8 in __GI___libc_free (mem=...) at ./malloc/malloc.c:3375
#8  0x0000555555566a5c in Renderer::Render() ()
#9  0x00005555555590b6 in main ()
#7  0x00007ffff7ab6fa8 in __GI___libc_free (mem=...) at ./malloc/malloc.c:3375
#8  0x0000555555566a5c in Renderer::Render() ()
#9  0x00005555555590b6 in main ()
"""
HEAP_STRIPPED = """$1 = 6
$2 = (void *) 0x1f40
$3 = (void *) 0x7fffffffd160
#0  0x00007ffff7aa8eec in ?? () from /lib/x86_64-linux-gnu/libc.so.6
#1  0x00007ffff7a59fb2 in raise () from /lib/x86_64-linux-gnu/libc.so.6
#2  0x00007ffff7a44472 in abort () from /lib/x86_64-linux-gnu/libc.so.6
#3  0x00007ffff7a9d42f in ?? () from /lib/x86_64-linux-gnu/libc.so.6
#4  0x00007ffff7ab286a in ?? () from /lib/x86_64-linux-gnu/libc.so.6
#5  0x00007ffff7ab2a2c in ?? () from /lib/x86_64-linux-gnu/libc.so.6
#6  0x00007ffff7ab6fa8 in free () from /lib/x86_64-linux-gnu/libc.so.6
#7  0x0000555555566a5c in Renderer::Render() ()
#8  0x00005555555590b6 in main ()
#6  0x00007ffff7ab6fa8 in free () from /lib/x86_64-linux-gnu/libc.so.6
#7  0x0000555555566a5c in Renderer::Render() ()
#8  0x00005555555590b6 in main ()
"""
THROW = """$1 = 6
$2 = (void *) 0x20af
$3 = (void *) 0x7fffffffcee0
#0  0x00007ffff7aa8eec in ?? () from /lib/x86_64-linux-gnu/libc.so.6
#1  0x00007ffff7a59fb2 in raise () from /lib/x86_64-linux-gnu/libc.so.6
#2  0x00007ffff7a44472 in abort () from /lib/x86_64-linux-gnu/libc.so.6
#3  0x00007ffff7c9d919 in ?? () from /lib/x86_64-linux-gnu/libstdc++.so.6
#4  0x00007ffff7ca8e1a in ?? () from /lib/x86_64-linux-gnu/libstdc++.so.6
#5  0x00007ffff7ca8e85 in std::terminate() () from /lib/x86_64-linux-gnu/libstdc++.so.6
#6  0x00007ffff7ca90d8 in __cxa_throw () from /lib/x86_64-linux-gnu/libstdc++.so.6
#7  0x00007ffff7ca026d in ?? () from /lib/x86_64-linux-gnu/libstdc++.so.6
#8  0x0000555555566bf3 in Renderer::Render() ()
#9  0x00005555555590c6 in main ()
#7  0x00007ffff7ca026d in ?? () from /lib/x86_64-linux-gnu/libstdc++.so.6
#8  0x0000555555566bf3 in Renderer::Render() ()
#9  0x00005555555590c6 in main ()
"""
_TRACE = "in Renderer::traceRay(Ray const&, float, int, Hit&) const [clone .constprop.0] ()"
OVERFLOW = "\n".join([
    "$1 = 11", "$2 = (void *) 0x7fffff7feff8", "$3 = (void *) 0x7fffff7ff000",
    "#0  0x0000555555560e72 in Group::intersect(Ray const&, Hit&, float) const ()",
    "#1  0x0000555555564a78 " + _TRACE,
    *(f"#{n:<3}0x0000555555564dc5 {_TRACE}" for n in range(2, 40)),
    "#29102 0x0000555555564dc5 " + _TRACE,
    "#29103 0x0000555555565b08 in Renderer::Render() ()",
    "#29104 0x00005555555590b6 in main ()"])
# a build with debugging information (-g): gdb gives each frame's source line
HELPER_DEBUG = """$1 = 11
$2 = (void *) 0x0
$3 = (void *) 0x7fffffffd3f0
#0  0x0000555555567a10 in Image::setPixel (this=..., x=..., y=..., c=...) at src/Image.cpp:31
#1  0x0000555555565ec8 in Renderer::Render (this=...) at src/Renderer.cpp:55
#2  0x00005555555590a6 in main (argc=..., argv=...) at src/main.cpp:12
#0  0x0000555555567a10 in Image::setPixel (this=..., x=..., y=..., c=...) at src/Image.cpp:31
#1  0x0000555555565ec8 in Renderer::Render (this=...) at src/Renderer.cpp:55
#2  0x00005555555590a6 in main (argc=..., argv=...) at src/main.cpp:12
"""
PARSER = """$1 = 11
$2 = (void *) 0x8
$3 = (void *) 0x7fffffffd3f0
#0  0x0000555555567a10 in SceneParser::parseGroup() ()
#1  0x0000555555567b20 in SceneParser::SceneParser(char const*) ()
#2  0x0000555555565ec8 in Renderer::Renderer(ArgParser const&) ()
#3  0x00005555555590a6 in main ()
"""

# the solution writing row -1 (`--y` in the row loop): the write lands in the scene's objects,
# and the crash shows later, in Group::intersect called from traceRay
ROW_MINUS = """$1 = 11
$2 = (void *) 0x0
$3 = (void *) 0x7fffffffd280
#0  0x0000555555560ea5 in Group::intersect(Ray const&, Hit&, float) const ()
#1  0x0000555555564a68 in Renderer::traceRay(Ray const&, float, int, Hit&) const [clone ...] ()
#2  0x0000555555565c69 in Renderer::Render() ()
#3  0x00005555555590a6 in main ()
"""
_ALLOCATED = """  <auxwhat>Address 0x4d77e20 is 0 bytes after a block of size 32 alloc'd</auxwhat>
  <stack>
    <frame><fn>operator new(unsigned long)</fn></frame>
    <frame><fn>SceneParser::parseObject(SceneParser::Token const&amp;)</fn></frame>
    <frame><fn>Renderer::Renderer(ArgParser const&amp;)</fn></frame>
    <frame><fn>main</fn></frame>
  </stack>"""
# valgrind 3.19's XML of the same run, trimmed of the addresses and objects
ROW_MINUS_MEMCHECK = f"""<?xml version="1.0"?>
<valgrindoutput>
<protocolversion>4</protocolversion>
<error>
  <kind>Leak_PossiblyLost</kind>
  <stack><frame><fn>malloc</fn></frame><frame><fn>Material::shade</fn></frame></stack>
</error>
<error>
  <kind>InvalidWrite</kind>
  <what>Invalid write of size 8</what>
  <stack>
    <frame><fn>Renderer::Render()</fn></frame>
    <frame><fn>main</fn></frame>
  </stack>
{_ALLOCATED}
</error>
<error>
  <kind>InvalidRead</kind>
  <what>Invalid read of size 8</what>
  <stack>
    <frame><fn>Group::intersect(Ray const&amp;, Hit&amp;, float) const</fn></frame>
    <frame><fn>Renderer::traceRay(Ray const&amp;, float, int, Hit&amp;) const</fn></frame>
    <frame><fn>Renderer::Render()</fn></frame>
    <frame><fn>main</fn></frame>
  </stack>
  <auxwhat>Address 0x3f5f7e823f53597e is not stack'd, malloc'd or (recently) free'd</auxwhat>
</error>
<fatal_signal>
  <signo>11</signo>
  <signame>SIGSEGV</signame>
</fatal_signal>
</valgrindoutput>
"""


def evidence(log: str) -> tuple[tuple[str, ...], str] | None:
    trace = parse_backtrace(log)
    assert trace is not None
    site = located(trace)
    return None if site is None else (site.functions, site.evidence)


def test_a_signal_in_a_student_function_names_it():
    trace = parse_backtrace(FPE)
    assert trace is not None
    assert (trace.signal, trace.depth, trace.overflow) == (8, 2, False)
    assert trace.frames == (Frame(0, "Renderer::Render"), Frame(1, "main"))
    assert evidence(FPE) == (("Renderer::Render",), (
        "your program is killed by signal SIGFPE in Renderer::Render (gdb's stack, "
        "innermost first: Renderer::Render <- main)"))


@pytest.mark.parametrize("log", [HEAP, HEAP_STRIPPED], ids=["libc-symbols", "stripped-libc"])
def test_an_abort_in_the_allocator_says_the_heap_was_damaged_before(log: str):
    """With or without the C library's symbols: the allocator's SIGABRT is its heap check,
    found when Renderer::Render freed its vectors."""
    below = "__GI___libc_free" if log is HEAP else "free"
    assert evidence(log) == (("Renderer::Render",), (
        "your program is killed by signal SIGABRT: the C library found its heap damaged when "
        "Renderer::Render freed or allocated memory; a write out of bounds came before, into "
        "memory of Renderer::Render's or of a function it called (gdb's stack, innermost "
        f"first: {below} <- Renderer::Render <- main)"))


def test_an_exception_not_caught_names_the_function_that_threw():
    assert evidence(THROW) == (("Renderer::Render",), (
        "your program is killed by signal SIGABRT: an exception thrown in Renderer::Render was "
        "not caught (gdb's stack, innermost first: (a library's) <- Renderer::Render <- "
        "main)"))


def test_a_stack_overflow_names_the_function_that_calls_itself():
    """The fault is 8 bytes below the stack pointer: the guard page. Group::intersect, where
    the last call faulted, is not the one to blame."""
    trace = parse_backtrace(OVERFLOW)
    assert trace is not None and trace.overflow and trace.depth == 29105
    assert evidence(OVERFLOW) == (("Renderer::traceRay",), (
        "your program is killed by signal SIGSEGV: its stack overflowed, 29105 calls deep, "
        "Renderer::traceRay calling itself without end (gdb's stack, innermost first: "
        "Group::intersect <- Renderer::traceRay x39)"))


def test_a_crash_in_the_starters_code_names_the_student_function_that_called_it():
    assert evidence(HELPER_DEBUG) == (("Renderer::Render",), (
        "your program is killed by signal SIGSEGV in Image::setPixel, called from "
        "Renderer::Render (src/Renderer.cpp:55) (gdb's stack, innermost first: "
        "Image::setPixel <- Renderer::Render <- main)"))


def test_a_segv_after_a_write_out_of_bounds_names_where_memcheck_finds_the_write():
    """gdb alone would name traceRay, where the damage showed; memcheck's first invalid
    access (not the leak before it, not the read where it crashed) is Render's write."""
    trace = parse_backtrace(ROW_MINUS)
    assert trace is not None and not trace.overflow
    invalid = parse_memcheck(ROW_MINUS_MEMCHECK)
    assert invalid is not None
    assert [(i.what, [f.function for f in i.frames]) for i in invalid] == [
        ("Invalid write of size 8", ["Renderer::Render", "main"]),
        ("Invalid read of size 8", ["Group::intersect", "Renderer::traceRay",
                                    "Renderer::Render", "main"])]
    site = located(trace, invalid)
    assert site is not None and (site.functions, site.evidence) == (("Renderer::Render",), (
        "your program is killed by signal SIGSEGV; before that, valgrind's memcheck finds an "
        "invalid write of size 8 in Renderer::Render (memcheck's stack, innermost first: "
        "Renderer::Render <- main)"))


def test_an_access_through_a_pointer_gone_bad_elsewhere_names_nothing():
    """The read at a wild address alone: the pointer (a hit's material, an object) was made
    or damaged elsewhere, and the function that reads through it is not the one to blame."""
    trace = parse_backtrace(ROW_MINUS)
    invalid = parse_memcheck(ROW_MINUS_MEMCHECK)
    assert trace is not None and invalid is not None
    assert [i.out_of_bounds for i in invalid] == [True, False]
    assert located(trace, invalid[1:]) is None


# the solution whose normals array holds w - h = 0 values: its first invalid write, in
# Render, is through null (valgrind 3.19 said so of it, in the same words)
EMPTY_ARRAY_MEMCHECK = ROW_MINUS_MEMCHECK.replace(_ALLOCATED, (
    "  <auxwhat>Address 0x0 is not stack'd, malloc'd or (recently) free'd</auxwhat>"))


def test_a_null_pointer_in_renders_own_code_is_an_array_of_its_own():
    """Render is called by the starter's main and handed no pointer by a student function:
    a write near address 0 in its own code is through an array of its own (an empty
    std::vector's data is null). The same write in traceRay, whose hits carry materials the
    intersects set, names nothing."""
    trace = parse_backtrace(ROW_MINUS)
    invalid = parse_memcheck(EMPTY_ARRAY_MEMCHECK)
    assert trace is not None and invalid is not None
    site = located(trace, invalid)
    assert site is not None and (site.functions, site.evidence) == (("Renderer::Render",), (
        "your program is killed by signal SIGSEGV; before that, valgrind's memcheck finds an "
        "invalid write of size 8 near address 0 in Renderer::Render's own code, through a null "
        "pointer, as an array of its own that holds nothing has (memcheck's stack, innermost "
        "first: Renderer::Render <- main)"))
    in_trace = parse_memcheck(EMPTY_ARRAY_MEMCHECK.replace(
        "<frame><fn>Renderer::Render()</fn></frame>",
        "<frame><fn>Renderer::traceRay()</fn></frame><frame><fn>Renderer::Render()</fn>"
        "</frame>", 1))
    assert in_trace is not None and located(trace, in_trace) is None
    far = parse_memcheck(EMPTY_ARRAY_MEMCHECK.replace("0x0 is", "0x3f5f7e823f53597f is"))
    assert far is not None and located(trace, far) is None


def test_memcheck_killed_partway_stands_by_the_reports_it_finished():
    """A program that writes far past an array can damage valgrind's own memory: valgrind
    dies, its XML ends mid-report, and the whole reports before that are what it found."""
    cut = ROW_MINUS_MEMCHECK.index("<error>\n  <kind>InvalidRead")
    invalid = parse_memcheck(ROW_MINUS_MEMCHECK[:cut + 30])
    assert invalid is not None
    assert [(i.what, i.out_of_bounds) for i in invalid] == [("Invalid write of size 8", True)]
    trace = parse_backtrace(ROW_MINUS)
    assert trace is not None
    site = located(trace, invalid)
    assert site is not None and site.functions == ("Renderer::Render",)


# gdb 13's log of HANG_SCRIPT for the solution whose row loop never steps (`-+y`), at 2x2 on
# course/spheres_mirror: stopped in powf under Material::shade, every frame up to
# Renderer::Render returned
HANG = """Program received signal SIGINT, Interrupt.
log2_inline (ix=...) at ../sysdeps/ieee754/flt-32/e_powf.c:74
#0  log2_inline (ix=...) at ../sysdeps/ieee754/flt-32/e_powf.c:74
#1  __powf_fma (x=..., y=...) at ../sysdeps/ieee754/flt-32/e_powf.c:205
#2  0x000055555555f805 in Material::shade(Ray const&, Hit const&, Vector3f const&, \
Vector3f const&) ()
#3  0x0000555555564c5b in Renderer::traceRay(Ray const&, float, int, Hit&) const \
[clone .constprop.0] ()
#4  0x0000555555565c39 in Renderer::Render() ()
#5  0x00005555555590a6 in main ()
__powf_fma (x=..., y=...) at ../sysdeps/ieee754/flt-32/e_powf.c:206
0x000055555555f805 in Material::shade(Ray const&, Hit const&, Vector3f const&, \
Vector3f const&) ()
Value returned is $1 = 1.48234193e-07
0x0000555555564c5b in Renderer::traceRay(Ray const&, float, int, Hit&) const \
[clone .constprop.0] ()
0x0000555555565c39 in Renderer::Render() ()

Program received signal SIGINT, Interrupt.
0x0000555555565bb8 in Renderer::Render() ()
STUCK Renderer::Render()
[Inferior 1 (process 9355) killed]
"""


def test_a_program_that_runs_on_names_the_first_function_that_does_not_return():
    site = stuck(HANG)
    assert site is not None and (site.functions, site.evidence) == (("Renderer::Render",), (
        "your program runs past the time limit, and on a 2x2 image of the case too: stopped "
        "after 2 s, Renderer::Render does not return within 1 s more, while each call it was "
        "making did (gdb's stack, innermost first: Renderer::traceRay <- Renderer::Render <- "
        "main)"))
    # main stays (the starter's): no student function holds the program there
    assert stuck(HANG.replace("STUCK Renderer::Render()", "STUCK main")) is None
    # it finished on the small image, or gdb stopped early: no STUCK line
    assert stuck(HANG.split("STUCK")[0]) is None


class Replay:
    """A candidate whose debuggers print these outputs (None: not installed, out of time)."""

    def __init__(self, outputs: dict[Debugger, str | None]) -> None:
        self.outputs = outputs
        self.asked: list[Debugger] = []

    def debug(self, scene: Path, request: RenderRequest, debugger: Debugger) -> str | None:
        self.asked.append(debugger)
        return self.outputs[debugger]


@pytest.mark.parametrize("memcheck", [None, ROW_MINUS_MEMCHECK[:400]],
                         ids=["not-installed", "stopped"])
def test_a_segv_that_memcheck_cannot_look_into_names_nothing(memcheck: str | None):
    """Where the crash may be damage made elsewhere and memcheck gives no whole report, the
    crash site alone is not evidence enough."""
    candidate = Replay({Debugger.GDB: ROW_MINUS, Debugger.MEMCHECK: memcheck})
    assert crash_site(SHADOWS, RenderRequest(), candidate) is None  # type: ignore[arg-type]
    assert candidate.asked == [Debugger.GDB, Debugger.MEMCHECK]


def test_a_division_by_zero_needs_no_memcheck():
    candidate = Replay({Debugger.GDB: FPE, Debugger.MEMCHECK: None})
    found = crash_site(SHADOWS, RenderRequest(), candidate)  # type: ignore[arg-type]
    assert found is not None and found.message.startswith("Renderer::Render: your program ")
    assert candidate.asked == [Debugger.GDB]


def test_no_student_function_on_the_stack_names_none():
    assert evidence(PARSER) is None


def test_a_program_that_did_not_crash_under_gdb_gives_no_backtrace():
    assert parse_backtrace("No stack.\n") is None
    assert parse_backtrace("") is None


# --- the real solution, with a crash written into it -----------------------------------------
TRIANGLE = REPO / "scenes" / "features" / "triangle.txt"
NEEDS = [t for t in ("cmake", "g++", "gdb", "valgrind") if shutil.which(t) is None]
CRASHES = {
    # x = 0 divides by zero
    "fpe": Edit("src/Renderer.cpp", "color[y * w + x] = c", "color[y * w % x] = c"),
    # row -1 first: a write out of bounds whose damage crashes traceRay later
    "row_minus": Edit("src/Renderer.cpp", "for (int y = 0; y < h; ++y)",
                      "for (int y = 0; y < h; --y)"),
    # the mirror ray is the ray itself, at the same depth
    "overflow": Edit("src/Renderer.cpp", "traceRay(Ray(p + 0.01f * reflected, reflected), 0, "
                     "bounces - 1, mirrorHit)", "traceRay(r, 0, bounces, mirrorHit)"),
    # a depth buffer of one value: the writes past it kill valgrind too, partway
    "small_depth": Edit("src/Renderer.cpp", "depth(w * h)", "depth(w / h)"),
    # the row loop never steps: row 0 again and again
    "hang": Edit("src/Renderer.cpp", "for (int y = 0; y < h; ++y)",
                 "for (int y = 0; y < h; -+y)"),
    # a Transform that reports a hit where its object is missed: where nothing else is hit,
    # traceRay shades the hit's null material
    "null_hit": Edit("src/Object3D.cpp", "if (!o->intersect(Ray(origin, dir), h, tmin))",
                     "if (o->intersect(Ray(origin, dir), h, tmin))"),
}


@pytest.mark.full  # three builds of the solution, cached after the first run
@pytest.mark.skipif(bool(NEEDS), reason=f"not installed: {', '.join(NEEDS)}")
@pytest.mark.parametrize("sandbox", ["off", "required"])
def test_the_check_of_a_crashing_program_leads_with_where_it_crashed(tmp_path: Path,
                                                                     sandbox: str):
    """`raycheck check` of the solution dividing by zero in Renderer::Render, of one writing
    row -1, of one whose mirror recursion never ends, of one whose depth buffer holds one
    value, and of one whose row loop never ends: every case it crashes on leads with
    the function, then the crash; in the sandbox too, where gdb and valgrind run inside it."""
    if sandbox == "required" and unavailable_reason() is not None:
        pytest.skip(f"no sandbox here: {unavailable_reason()}")
    fpe = build_solution(copy_solution(tmp_path / "fpe", (CRASHES["fpe"],)))
    got = run_check(tmp_path / "out-fpe", str(fpe), [SHADOWS], "plain", "--sandbox", sandbox)
    assert got.code == 1
    for case in got.data["cases"]:
        located, crash = case["findings"]
        assert located == {"code": "located", "message": (
            "Renderer::Render: your program gives no image of this case; the evidence points "
            "here: your program is killed by signal SIGFPE in Renderer::Render (gdb's "
            "stack, innermost first: Renderer::Render <- main)"),
            "functions": ["Renderer::Render"]}
        assert crash == {"code": "crash", "message": "killed by signal SIGFPE"}
    row_minus = build_solution(copy_solution(tmp_path / "row_minus", (CRASHES["row_minus"],)))
    # at 48 pixels, row -1 (576 bytes before the image's array) lands inside the block before
    # it in triangle.txt, beyond memcheck's default redzone of 16 bytes: its own wider one
    # reports the write as before the array
    got = run_check(tmp_path / "out-row", str(row_minus), [SHADOWS, TRIANGLE], "plain",
                    "--sandbox", sandbox, size=("48", "48"))
    assert len(got.data["cases"]) == 6
    led_by(got, "Renderer::Render", "your program is killed by signal SIGSEGV; before that, "
           "valgrind's memcheck finds an invalid write of size 8 in Renderer::Render")
    overflow = build_solution(copy_solution(tmp_path / "overflow", (CRASHES["overflow"],)))
    got = run_check(tmp_path / "out-overflow", str(overflow), [MIRROR], "plain,bounces",
                    "--sandbox", sandbox)
    assert {(c["feature"], c["verdict"]) for c in got.data["cases"]} == {
        ("plain", "pass"), ("bounces4", "error")}
    for lead, crash in led_by(got, "Renderer::traceRay", "your program is killed by "
                                 "signal SIGSEGV: its stack overflowed, "):
        assert "Renderer::traceRay calling itself without end" in lead["message"]
        assert crash == {"code": "crash", "message": "killed by signal SIGSEGV"}
    small = build_solution(copy_solution(tmp_path / "small_depth", (CRASHES["small_depth"],)))
    got = run_check(tmp_path / "out-small", str(small), [SHADOWS], "plain", "--sandbox",
                    sandbox, size=("48", "48"))
    led_by(got, "Renderer::Render", "your program is killed by signal SIGSEGV; before that, "
           "valgrind's memcheck finds an invalid write of size 4 in Renderer::Render")
    hang = build_solution(copy_solution(tmp_path / "hang", (CRASHES["hang"],)))
    got = run_check(tmp_path / "out-hang", str(hang), [SHADOWS], "plain", "--sandbox",
                    sandbox, "--timeout", "5")
    for _, timeout in led_by(got, "Renderer::Render", "your program runs past the time "
                             "limit, and on a 2x2 image of the case too: stopped after 2 s, "
                             "Renderer::Render does not return within 1 s more"):
        assert timeout == {"code": "timeout", "message": "no result after 5 s (killed)"}


@pytest.mark.full  # a build of the solution, cached after the first run
@pytest.mark.skipif(bool(NEEDS), reason=f"not installed: {', '.join(NEEDS)}")
def test_a_crash_on_the_scenes_with_transforms_alone_names_transform(tmp_path: Path):
    """The solution whose Transform::intersect reports a hit where its object is missed: on
    shadows.txt (a transformed mesh) a ray that hits nothing is shaded with a null material and
    the program crashes where no debugger's frame says who made the hit; on cubemap_mesh.txt
    and spheres_mirror.txt, which transform nothing, it passes. Transform::intersect alone runs
    in the one and in neither other."""
    null_hit = build_solution(copy_solution(tmp_path / "null_hit", (CRASHES["null_hit"],)))
    got = run_check(tmp_path / "out", str(null_hit), [SHADOWS, MESH, MIRROR], "plain")
    assert {(c["scene"], c["verdict"]) for c in got.data["cases"]} == {
        ("features/shadows", "error"), ("course/cubemap_mesh", "pass"),
        ("course/spheres_mirror", "pass")}
    led_by(got, "Transform::intersect", "it is killed by signal SIGSEGV on every case of the "
           "1 scene holding transformed objects (features/shadows) and passes every case of "
           "the 2 scenes without (course/cubemap_mesh, course/spheres_mirror)")


def led_by(got, function: str, evidence: str) -> list[list[dict]]:
    """The findings of each case that erred (one at least), led by a located finding of
    `function` whose evidence starts with `evidence`."""
    erred = [c["findings"] for c in got.data["cases"] if c["verdict"] == "error"]
    assert erred
    for lead, *_ in erred:
        assert lead["message"].startswith(
            f"{function}: your program gives no image of this case; the evidence points "
            f"here: {evidence}"), lead
    return erred
