"""Where a compiled program crashed, read off gdb's backtrace of the same render and, where
the crash may be damage done elsewhere, valgrind's memcheck of it (CommandRenderer.debug), as
a `located` finding naming the starter function to look at.

The rules, each from what a crash means, not from any program's bugs:
* a write out of bounds may crash the program far from where it was made (a SIGSEGV or
  SIGBUS in code that reads what it damaged, the allocator's abort when it frees): memcheck
  reports each invalid access where it is made, and the first one just outside a heap block
  (within memcheck's redzone about it, 4 KiB: an index past an array's end or before its
  start, computed there) names its innermost student function. An
  access through a wild, null or freed pointer names none: the pointer went bad elsewhere
  (a hit whose material was never set crashes in Material::shade), but for one through a
  null pointer in Renderer::Render's own code: no student function hands it a pointer, so the
  array it reads or writes there is its own, and holds nothing (an empty std::vector). Where
  memcheck cannot say (not installed, out of time), none is named;
* otherwise the signal's frame is where the program went wrong, but a frame of code the
  starter gives (Image::setPixel, Group::intersect, vecmath) or of a library (std::vector,
  the C library) did what it was asked: the bad value came from the student-filled function
  that called it, the innermost such function on the stack;
* a SIGSEGV at the stack pointer is a stack overflow: the frames are a recursion without end,
  and the student function repeated most among the innermost frames is the one that does not
  stop calling itself (wherever the last call happened to fault);
* where the allocator aborts and memcheck sees no invalid access, the student function that
  freed or allocated is the one to read first, and the finding says that a write came before;
* an exception that no one catches aborts in the function that threw it.
A stack with no student-filled function on it (a crash while parsing the scene) names none.

A program that runs past the time limit runs again on a TINY x TINY image of the case, where
a slow one finishes and one whose loop never ends does not, under gdb (Debugger.HANG): stopped
after a while, each function on its stack, innermost first, is let run until it returns, and
the first that does not is where the program stays (each call it made returned); the
innermost student-filled function at or outside it is named.
"""
from __future__ import annotations

import re
import signal
from collections import Counter
from dataclasses import dataclass, replace
from pathlib import Path
from xml.etree import ElementTree

from raycheck.tracer.scene.request import RenderRequest

from ..judge.findings import Finding
from ..renderers import Debuggable, Debugger, Renderer
from ..renderers.command import HANG_STEP_S, HANG_WAIT_S
from .localise import NO_IMAGE, Located

# the functions the assignment's starter code leaves to the student
STUDENT_FUNCTIONS = frozenset({
    "PointLight::getIllumination", "DirectionalLight::getIllumination", "Material::shade",
    "Renderer::traceRay", "Renderer::Render", "Sphere::intersect", "Plane::Plane",
    "Plane::intersect", "Triangle::intersect", "Transform::intersect"})
# the side of the image a program that runs past the time limit runs again on
TINY = 2
# an access this close to address 0 (bytes) is through a null pointer
NULL_REACH = 1 << 16
# the student function the starter's main calls, handed no pointer by any student function:
# one it reads or writes through near address 0 in its own code is its own
OWN_POINTERS = "Renderer::Render"
# a fault this close to the stack pointer (bytes) is the stack's guard page
STACK_REACH = 1 << 16
STACK_SHOWN = 6  # the frames a finding shows (a run of one function's counts once)
# the allocator's functions, by their exported names and (with the C library's debugging
# information) their internal ones: a SIGABRT below one of them is its check of the heap
ALLOCATOR = frozenset({
    "free", "malloc", "calloc", "realloc", "operator delete", "operator new",
    "__GI___libc_free", "__libc_free", "__GI___libc_malloc", "__libc_malloc",
    "__GI___libc_realloc", "__libc_realloc", "_int_free", "_int_malloc", "malloc_printerr"})
# the C++ runtime's functions that throw, or end the program for an exception not caught
THROWS = frozenset({"__cxa_throw", "__cxa_rethrow", "std::terminate"})
UNKNOWN = "??"  # gdb's name for a frame of a library without symbols
# memcheck's kinds of an access out of bounds or to freed memory (not leaks, not reads of
# uninitialised values: those do not crash)
MEMORY_ERRORS = frozenset({"InvalidRead", "InvalidWrite", "InvalidFree", "MismatchedFree",
                           "InvalidJump"})

_FRAME = re.compile(r"^#(\d+)\s+(?:0x[0-9a-fA-F]+ in )?(.*)$")
_VALUE = re.compile(r"^\$(\d+) = (?:\([^)]*\) )?(-?(?:0x[0-9a-fA-F]+|\d+))")


@dataclass(frozen=True)
class Frame:
    number: int
    function: str        # qualified, without its parameters: "Renderer::traceRay"
    location: str = ""   # "src/Renderer.cpp:107" where the program has debug information

    @property
    def student(self) -> bool:
        return self.function in STUDENT_FUNCTIONS


@dataclass(frozen=True)
class Backtrace:
    """What GDB_SCRIPT printed: the signal, the faulting address and the stack pointer, the
    innermost frames, and the stack's depth."""

    signal: int
    fault: int | None
    stack_pointer: int | None
    frames: tuple[Frame, ...]  # innermost first
    depth: int

    @property
    def overflow(self) -> bool:
        return self.signal == signal.SIGSEGV and self.fault is not None and \
            self.stack_pointer is not None and abs(self.fault - self.stack_pointer) <= STACK_REACH


def parse_backtrace(text: str) -> Backtrace | None:
    """The backtrace gdb's script printed, or None where it holds no signal or no frame (the
    program ran to its end under gdb)."""
    values = [int(v[2], 0) for line in text.splitlines() if (v := _VALUE.match(line))]
    frames = _frames(text)
    if not values or not frames:
        return None
    return Backtrace(values[0], values[1] if len(values) > 1 else None,
                     values[2] if len(values) > 2 else None,
                     tuple(f for f in frames if f.number < 40), frames[-1].number + 1)


def _frames(text: str) -> tuple[Frame, ...]:
    """gdb's frames in `text`, innermost first, each number once (the first `bt`'s)."""
    frames: dict[int, Frame] = {}
    for line in text.splitlines():
        frame = _FRAME.match(line)
        if frame:
            frames.setdefault(int(frame[1]), _frame(int(frame[1]), frame[2]))
    return tuple(frames[n] for n in sorted(frames))


def _frame(number: int, text: str) -> Frame:
    """A frame from gdb's line: `Renderer::Render() ()`, `Renderer::traceRay (...) at
    src/Renderer.cpp:107`, `__GI_abort () at ./stdlib/abort.c:79`, `foo () from /lib/x.so`;
    a lambda's `Renderer::Render()::{lambda(...)#1}::operator()(...)` is its function's."""
    name = text.split("(", 1)[0].strip()
    location = re.search(r" at (\S+:\d+)$", text)
    return Frame(number, name, location[1] if location else "")


@dataclass(frozen=True)
class Invalid:
    """One invalid read or write memcheck reports: what ("Invalid write of size 8") and its
    stack, innermost first."""

    what: str
    frames: tuple[Frame, ...]
    address: str = ""  # "Address 0x4d77e20 is 0 bytes after a block of size 32 alloc'd"

    @property
    def near_null(self) -> bool:
        """Whether the address is within NULL_REACH of address 0: a null pointer and an
        offset (an array that holds nothing: an empty std::vector's data is null)."""
        found = re.search(r"Address (0x[0-9a-fA-F]+) is not stack'd", self.address)
        return found is not None and int(found[1], 16) < NULL_REACH

    @property
    def out_of_bounds(self) -> bool:
        """Whether the address is just outside a heap block: an index past an array's end,
        computed where the access is; else a pointer from elsewhere (wild, null, freed)."""
        return re.search(r" bytes (before|after) a block of size [\d,]+ alloc'd", self.address) \
            is not None


def parse_memcheck(xml: str) -> tuple[Invalid, ...] | None:
    """The invalid accesses (reads, writes, frees, jumps) valgrind's XML reports, in the order
    made. Where the XML ends early, those whose reports are whole: a program that writes far
    out of bounds can damage valgrind's own memory and kill it, and what it reported before
    stands; but not the absence of one. None where the XML is not whole and holds no whole
    report of an invalid access (valgrind was stopped early, or did not run)."""
    truncated = False
    try:
        errors = list(ElementTree.fromstring(xml).iter("error"))
    except ElementTree.ParseError:
        truncated = True
        try:
            errors = [ElementTree.fromstring(e)
                      for e in re.findall(r"<error>.*?</error>", xml, re.DOTALL)]
        except ElementTree.ParseError:
            return None
    found = []
    for error in errors:
        if (error.findtext("kind") or "") not in MEMORY_ERRORS:
            continue
        stack = error.find("stack")  # the first: where it was made (others: where allocated)
        frames = () if stack is None else tuple(
            Frame(i, (f.findtext("fn") or UNKNOWN).split("(", 1)[0].strip(),
                  f"{f.findtext('file')}:{f.findtext('line')}" if f.find("line") is not None
                  else "")
            for i, f in enumerate(stack.iter("frame")))
        found.append(Invalid(error.findtext("what") or "", frames,
                             error.findtext("auxwhat") or ""))
    return None if truncated and not found else tuple(found)


def needs_memcheck(trace: Backtrace) -> bool:
    """Whether the crash may be the damage of an earlier write out of bounds, somewhere else:
    a SIGSEGV or SIGBUS that is no stack overflow, or the allocator's abort."""
    inner = {f.function for f in trace.frames}
    return (trace.signal in (signal.SIGSEGV, signal.SIGBUS) and not trace.overflow) or \
        (trace.signal == signal.SIGABRT and bool(inner & ALLOCATOR))


def located(trace: Backtrace, invalid: tuple[Invalid, ...] = ()) -> Located | None:
    """The student function the backtrace points at (the rules above), or the first invalid
    access memcheck found before the crash, with the evidence; None where no student
    function is on the stack."""
    crash = f"is killed by signal {_signal_name(trace.signal)}"
    if trace.overflow:
        counts = Counter(f.function for f in trace.frames if f.student)
        if not counts:
            return None
        function, _ = counts.most_common(1)[0]
        return Located((function,), f"your program {crash}: its stack overflowed, "
                       f"{trace.depth} calls deep, {function} calling itself without end "
                       f"{_told(trace.frames)}")
    if invalid:
        first = next((i for i in invalid if i.out_of_bounds
                      and any(f.student for f in i.frames)), None)
        if first is None and invalid[0].near_null and invalid[0].frames \
                and invalid[0].frames[0].function == OWN_POINTERS:
            return Located((OWN_POINTERS,), (
                f"your program {crash}; before that, valgrind's memcheck finds an "
                f"{invalid[0].what[:1].lower()}{invalid[0].what[1:]} near address 0 in "
                f"{OWN_POINTERS}'s own code, through a null pointer, as an array of its own "
                f"that holds nothing has {_told(invalid[0].frames, 'memcheck')}"))
        if first is None:  # a pointer gone bad elsewhere: the access does not say where
            return None
        student, where = _where(first.frames)
        return Located((student.function,), (
            f"your program {crash}; before that, valgrind's memcheck finds an "
            f"{first.what[:1].lower()}{first.what[1:]}{where} {_told(first.frames, 'memcheck')}"))
    at = next((i for i, f in enumerate(trace.frames) if f.student), None)
    if at is None:
        return None
    student, where = _where(trace.frames)
    named = _named(student)
    inner = {f.function for f in trace.frames[:at]}
    if trace.signal == signal.SIGABRT and inner & ALLOCATOR:
        what = (f": the C library found its heap damaged when {named} freed or allocated "
                "memory; a write out of bounds came before, into memory of "
                f"{student.function}'s or of a function it called")
    elif inner & THROWS:
        what = f": an exception thrown in {named} was not caught"
    else:
        what = where
    return Located((student.function,), f"your program {crash}{what} "
                   f"{_told(trace.frames[max(0, at - 1):])}")


def _where(frames: tuple[Frame, ...]) -> tuple[Frame, str]:
    """The innermost student frame, and where the stack's innermost frame is in words: " in
    F (file:line)" or " in X, called from F"."""
    at = next(i for i, f in enumerate(frames) if f.student)
    student = frames[at]
    named = _named(student)
    called = next((f.function for f in frames[:at] if f.function != UNKNOWN),
                  "a library function")
    return student, (f" in {called}, called from {named}" if at else f" in {named}")


def _named(frame: Frame) -> str:
    """The frame's function, with its source line where the program has one."""
    return frame.function + (f" ({frame.location})" if frame.location else "")


def _told(frames: tuple[Frame, ...], tool: str = "gdb") -> str:
    """The frames as the tool's stack has them, innermost first, repeats counted, the first
    STACK_SHOWN."""
    runs: list[list] = []
    for frame in frames:
        name = "(a library's)" if frame.function == UNKNOWN else frame.function
        if runs and runs[-1][0] == name:
            runs[-1][1] += 1
        else:
            runs.append([name, 1])
    shown = [name if n == 1 else f"{name} x{n}" for name, n in runs[:STACK_SHOWN]]
    more = " <- ..." if len(runs) > STACK_SHOWN else ""
    return f"({tool}'s stack, innermost first: {' <- '.join(shown)}{more})"


def _signal_name(number: int) -> str:
    try:
        return signal.Signals(number).name
    except ValueError:
        return str(number)


def crash_site(scene: Path, request: RenderRequest, candidate: Renderer) -> Finding | None:
    """The located finding of a candidate that crashed: where gdb finds it crashing on the
    same request, or where memcheck finds the write out of bounds before it, if the candidate
    is a native program that crashes again with a student function on its stack. Where the
    crash may be such damage and memcheck cannot say (not installed, out of time), none."""
    if not isinstance(candidate, Debuggable):
        return None
    text = candidate.debug(scene, request, Debugger.GDB)
    trace = None if text is None else parse_backtrace(text)
    if trace is None:
        return None
    invalid: tuple[Invalid, ...] = ()
    if needs_memcheck(trace):
        xml = candidate.debug(scene, request, Debugger.MEMCHECK)
        found = None if xml is None else parse_memcheck(xml)
        if found is None:
            return None
        invalid = found
    site = located(trace, invalid)
    return None if site is None else site.finding(NO_IMAGE)


def stuck(text: str) -> Located | None:
    """Where gdb's HANG_SCRIPT found a program staying (its first stack and the function that
    did not return, STUCK), as the innermost student function at or outside that frame;
    None where it found none or no student function holds it."""
    found = re.search(r"^STUCK (.+)$", text, re.MULTILINE)
    if found is None:
        return None
    stack = _frames(text[:found.start()])
    name = _frame(0, found[1]).function
    at = next((i for i, f in enumerate(stack) if f.function == name), None)
    student = None if at is None else next((f for f in stack[at:] if f.student), None)
    if student is None:
        return None
    inner = stack.index(student)
    return Located((student.function,), (
        f"your program runs past the time limit, and on a {TINY}x{TINY} image of the case "
        f"too: stopped after {HANG_WAIT_S:g} s, {student.function} does not return within "
        f"{HANG_STEP_S:g} s more, while each call it was making did "
        f"{_told(stack[max(0, inner - 1):])}"))


def hang_site(scene: Path, request: RenderRequest, candidate: Renderer) -> Finding | None:
    """The located finding of a candidate that ran past the time limit: where gdb finds it
    staying on a TINY x TINY image of the case, if the candidate is a native program that
    runs on there too."""
    if not isinstance(candidate, Debuggable):
        return None
    text = candidate.debug(scene, replace(request, width=TINY, height=TINY), Debugger.HANG)
    site = None if text is None else stuck(text)
    return None if site is None else site.finding(NO_IMAGE)
