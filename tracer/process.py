"""The contract every raycheck command keeps with its caller, whatever process runs it: exit
status 0 success, 1 a check failed, 2 bad usage or input, 130 interrupted (Ctrl-C, SIGINT), 143
terminated (SIGTERM); an expected failure is one line on stderr; an interrupt at any moment
(parsing, tracing or compiling a kernel, launching it, reading back, writing files, waiting for
a worker) ends the command with one line and its status, after the cleanups an exception runs
(no output file half written, no staging folder, no process left behind), up to the moment
its output is final (finish_run): from there it ends as finished. Never a traceback.

This module imports nothing heavy: the console scripts call it before they import the
commands, so that an interrupt while those load is handled too.
"""
from __future__ import annotations

import contextlib
import os
import signal
import sys
import threading
from typing import Callable, Iterator

EXIT_OK, EXIT_USAGE = 0, 2
_SIGNALS = (signal.SIGINT, signal.SIGTERM)
RESEND_S = 0.01  # an interrupt Python could not raise is sent again after this


class Terminated(KeyboardInterrupt):
    """SIGTERM, raised as Python raises KeyboardInterrupt for SIGINT: every cleanup that runs
    for Ctrl-C runs for it too."""


def signal_of(interrupt: KeyboardInterrupt) -> int:
    """The signal behind an interrupt: SIGTERM for Terminated, and for a plain
    KeyboardInterrupt where SIGTERM was the signal raised (a C extension that re-raises an
    interrupt of the code it runs may make a new KeyboardInterrupt of a Terminated)."""
    if isinstance(interrupt, Terminated) or _last_signal == signal.SIGTERM:
        return signal.SIGTERM
    return signal.SIGINT


def exit_status(interrupt: KeyboardInterrupt) -> int:
    """128 + the signal's number, as a shell reports a process the signal ended."""
    return 128 + signal_of(interrupt)


def interrupt_in(error: BaseException) -> KeyboardInterrupt | None:
    """The interrupt behind `error`: itself, or one among its causes and contexts. Dr.Jit
    re-raises an exception of the code it traces as a RuntimeError of its own with the original
    as its cause (backend.traced_errors_unwrapped takes them off where it can),
    and an interrupt that
    lands while a C extension is imported comes out as that import's SystemError or NameError,
    with the interrupt as its context."""
    todo: list[BaseException | None] = [error]
    seen: set[int] = set()
    while todo:
        e = todo.pop()
        if e is None or id(e) in seen:
            continue
        if isinstance(e, KeyboardInterrupt):
            return e
        seen.add(id(e))
        todo += [e.__cause__, e.__context__]
    return None


_depth = 0  # interrupts_raised blocks open (main thread)
_raised = False  # an interrupt has been raised since the outermost block began
_deferring = 0  # signals_deferred blocks open
_pending: int | None = None  # a signal that arrived in one, to raise when it ends
_ignoring = False  # ignore_interrupts was called: the process is ending
_last_signal: int | None = None  # the signal raise_interrupt last raised as an interrupt
_raises = 0  # interrupts raised in this process, by the handler or raise_swallowed
_finished = False  # the command's outcome is final (finish_run): no interrupt is raised


def swallowed_interrupt() -> KeyboardInterrupt | None:
    """The interrupt raised in the open interrupts_raised block where the error that ended it
    no longer carries it: a C extension caught it and raised an error of its own (numpy's core,
    interrupted while it imports `datetime`, raises an ImportError with no trace of it). The
    process was asked to stop; what failed after that is the stop's doing."""
    if not _raised or _last_signal is None:
        return None
    return Terminated() if _last_signal == signal.SIGTERM else KeyboardInterrupt()


def raise_swallowed() -> None:
    """Raises again the interrupt that swallowed_interrupt finds where the work went on after
    it: code caught it as its own error. The standard library's ElementTree does `from
    _elementtree import *` under `except ImportError`; interrupted while that C module imports
    pyexpat, PyCapsule_Import replaces the interrupt with an ImportError, which is dropped.
    Called once a command's modules are loaded and before each step that makes a run's outcome
    final (files renamed into place, a folder swapped in)."""
    global _raises
    interrupt = swallowed_interrupt()
    if interrupt is not None:
        _raises += 1
        raise interrupt


def raise_interrupt(signum: int, _frame=None) -> None:
    """The handler of SIGINT and SIGTERM (interrupts_raised): raises the interrupt, or keeps
    it for the end of a signals_deferred block."""
    global _raised, _pending, _last_signal, _raises
    # a second Ctrl-C while the first one's cleanups run: they run to their end; and once
    # the output is final, the command ends as finished
    if _raised or _finished:
        return
    if _deferring:
        _pending = signum
        return
    _raised, _last_signal, _raises = True, signum, _raises + 1
    if _in_finalizer(_frame):
        _send_later(signum)
        return
    raise Terminated() if signum == signal.SIGTERM else KeyboardInterrupt()


def _in_finalizer(frame) -> bool:
    """Whether `frame` runs within one of multiprocessing's finalizers. Raised there, the
    interrupt could not leave the weakref callback that runs them, and would cut it in half: a
    semaphore unlinked but not yet unregistered makes the resource tracker print warnings after
    the command's one line."""
    util = sys.modules.get("multiprocessing.util")
    if util is None:
        return False
    finalizer = util.Finalize.__call__.__code__
    while frame is not None:
        if frame.f_code is finalizer:
            return True
        frame = frame.f_back
    return False


@contextlib.contextmanager
def interrupts_raised() -> Iterator[None]:
    """Within the block, SIGINT raises KeyboardInterrupt and SIGTERM Terminated, once: a second
    signal while the first one's exception unwinds is ignored, so that the cleanups it sets off
    (removing a staging folder, stopping worker processes, killing a renderer's process group)
    end. A signal the process was started ignoring (a background job's SIGINT) stays ignored.
    Only the main thread can set handlers: elsewhere the block changes nothing."""
    global _depth, _raised, _last_signal, _finished
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    if _depth == 0:
        _last_signal = None
    previous = {s: signal.getsignal(s) for s in _SIGNALS}
    for s, handler in previous.items():
        if handler is not signal.SIG_IGN:
            signal.signal(s, raise_interrupt)
    previous_hook, sys.unraisablehook = sys.unraisablehook, reraising_hook(sys.unraisablehook)
    previous_excepthook, sys.excepthook = sys.excepthook, silent_on_interrupt(sys.excepthook)
    _depth += 1
    try:
        yield
    finally:
        sys.excepthook = previous_excepthook
        sys.unraisablehook = previous_hook
        if not _ignoring:
            for s, handler in previous.items():
                signal.signal(s, handler)
        _depth -= 1
        if _depth == 0:
            _raised = _finished = False


def finish_run() -> None:
    """The command's outcome is final: its output is in place (an output folder swapped in).
    From here to its status, within the outermost interrupts_raised block, a signal is no
    longer raised: status 130 says that the previous output stands, which is no longer so, and
    what is left (closing files, printing a summary) is short. Call it where the step that
    makes the outcome final has just happened, within signals_deferred: a signal held back
    there is dropped too."""
    global _finished
    if threading.current_thread() is threading.main_thread() and _depth:
        _finished = True


def reraising_hook(previous: Callable) -> Callable:
    """A sys.unraisablehook (`previous` for everything else) that raises an interrupt again
    which Python could not raise where it
    landed (a weakref callback, a __del__ method: "Exception ignored in ..."): the signal is
    sent once more a moment later, from another thread (sent now, its handler would run inside
    this hook, which cannot raise either), and raised where the main thread then is."""
    def hook(unraisable) -> None:
        interrupt = interrupt_in(unraisable.exc_value) if unraisable.exc_value else None
        if interrupt is None:
            previous(unraisable)
            return
        # _raised stays set until the other thread sends the signal: one that arrives while
        # this hook runs (starting that thread waits) is ignored rather than raised in here
        _send_later(signal_of(interrupt))

    return hook


def silent_on_interrupt(previous: Callable) -> Callable:
    """A sys.excepthook (`previous` for everything else) that prints nothing for an interrupt,
    nor for any error once one has been raised in the block. Within a command only C code calls
    the hook, through PyErr_Print: numpy's import_array prints the error that stopped its import
    (an interrupt that landed in it, or the ImportError it made of one) and raises an ImportError
    of its own, which interruptible then answers with its one line."""
    def hook(kind, value, traceback) -> None:
        if interrupt_in(value) is None and swallowed_interrupt() is None:
            previous(kind, value, traceback)

    return hook


def _send_later(signum: int) -> None:
    """Sends `signum` to this process again RESEND_S from now, from another thread, unless
    an interrupt is raised meanwhile; _raised stays set until then."""
    again = threading.Timer(RESEND_S, _send_again, (signum, _raises))
    again.daemon = True
    again.start()


def _send_again(signum: int, raises: int) -> None:
    global _raised
    if _raises != raises:  # raised again meanwhile (raise_swallowed): once is enough
        return
    _raised = False
    os.kill(os.getpid(), signum)


@contextlib.contextmanager
def signals_deferred() -> Iterator[None]:
    """An interrupt that arrives within the block is raised when it ends: for steps that must
    all happen or none (renaming a run's files into place, swapping an output folder). Only
    where interrupts_raised handles the signals; elsewhere the block changes nothing."""
    global _deferring, _pending
    _deferring += 1
    try:
        yield
    finally:
        _deferring -= 1
        signum, _pending = (_pending, None) if _deferring == 0 else (None, _pending)
        if signum is not None:
            raise_interrupt(signum, None)


def current_umask() -> int:
    """The process's umask. Reading it means setting it (to 0, then back): an interrupt between
    the two would leave the process making files anyone may write, so it waits for both."""
    with signals_deferred():
        mask = os.umask(0)
        os.umask(mask)
    return mask


def ignore_interrupts() -> None:
    """SIGINT and SIGTERM ignored for the rest of the process (main thread only): the command
    has its status and its output is complete; an interrupt while the interpreter and Dr.Jit
    tear down would only turn that status into death by the signal."""
    global _ignoring
    if threading.current_thread() is threading.main_thread():
        _ignoring = True
        for s in _SIGNALS:
            signal.signal(s, signal.SIG_IGN)


def interruptible(prog: str, action: Callable[[], int], *, ending: bool = False) -> int:
    """action()'s status, or after an interrupt (interrupt_in) one line on stderr naming
    `prog` and status 130 (143 for SIGTERM). ending: the process ends after this, and ignores
    interrupts once the status is known (ignore_interrupts)."""
    with interrupts_raised():
        try:
            status = action()
            if ending:
                ignore_interrupts()
            return status
        except BaseException as e:  # noqa: BLE001 - the interrupts, anywhere in its chain
            interrupt = interrupt_in(e) or swallowed_interrupt()
            if interrupt is None:
                raise
        word = "terminated" if signal_of(interrupt) == signal.SIGTERM else "interrupted"
        print(f"{prog}: {word}", file=sys.stderr, flush=True)
        if ending:
            ignore_interrupts()
        return exit_status(interrupt)


def run_command(prog: str, action: Callable[[], int],
                expected: tuple[type[Exception], ...] = (), uses_cache: bool = True) -> int:
    """Runs a command line's action (interruptible). The expected errors (bad flags, bad files,
    limits), OS errors and running out of memory end in one line on stderr and exit status 2.
    Float arithmetic follows IEEE (inf, NaN) as in the course's C code, without numpy
    warnings. An action that uses_cache first has its size setting checked (a help text does
    not need it)."""
    from .scene.errors import printable

    def guarded() -> int:
        import numpy as np

        from .cache import CacheSettingError, size_limit

        caught: tuple[type[BaseException], ...] = (*expected, CacheSettingError, OSError,
                                                   MemoryError)

        try:
            with np.errstate(all="ignore"):
                if uses_cache:
                    size_limit()  # before any work: every write to raycheck's cache prunes by it
                return action()
        except BrokenPipeError:  # whoever read our output went away (`| head`): nothing to say
            os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
            return EXIT_OK
        except caught as e:
            if interrupt_in(e) is not None:  # a cleanup's failure after Ctrl-C
                raise
            message = failure_message(e, (*expected, CacheSettingError))
        print(printable(f"{prog}: error: {message}"), file=sys.stderr)
        return EXIT_USAGE

    return interruptible(prog, guarded)


def failure_message(e: BaseException, expected: tuple[type[BaseException], ...]) -> str:
    """The one line that says what went wrong: an expected error's own message, an OS error's
    file and reason."""
    if isinstance(e, expected):
        return str(e)
    if isinstance(e, MemoryError):
        return "out of memory"
    detail = getattr(e, "strerror", None) or str(e) or type(e).__name__
    filename = getattr(e, "filename", None)
    return f"{filename}: {detail}" if filename else detail
