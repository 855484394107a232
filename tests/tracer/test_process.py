"""The process contract (tracer/process.py) in this process: an interrupt wherever it lands
(inside code Dr.Jit traces, inside a cleanup, inside steps that must all happen) ends the
action with one line and 130 or 143. (tests/harness/test_interrupt.py sends real signals to real
commands at random moments.)"""
from __future__ import annotations

import ctypes
import os
import signal
import sys
import threading
import time
from pathlib import Path

import pytest

from raycheck.harness.cli import main as raycheck_main
from raycheck.harness.storage.staging import ReplacedFolder
from raycheck.tracer.process import (
    Terminated,
    interrupt_in,
    interruptible,
    raise_swallowed,
    run_command,
    signals_deferred,
)
from raycheck.tracer.scene.outputs import write_all

REPO = Path(__file__).resolve().parents[2]
SPHERES = REPO / "scenes" / "course" / "spheres_mirror.txt"  # Phong highlights: powf


pytestmark = pytest.mark.usefixtures("python_sigint_handler")  # conftest.py


def test_ctrl_c_inside_a_traced_conditional_of_a_frozen_launch_is_an_interrupt(
        tmp_path, monkeypatch, capsys):
    """What a user met on a fresh machine: Ctrl-C while Dr.Jit traced the highlight's powf
    (a dr.if_stmt inside the dr.freeze recording of a launch) came out as Dr.Jit's
    RuntimeError ("dr.if_stmt(): encountered an exception"), a traceback and status 1."""
    import drjit

    def interrupted(*_args):
        raise KeyboardInterrupt

    monkeypatch.setattr(drjit, "log2", interrupted)  # powf's double branch calls it
    out = tmp_path / "a.png"
    code = raycheck_main(["render", "-input", str(SPHERES), "-size", "8", "8", "-output",
                          str(out)])
    assert code == 130
    assert capsys.readouterr().err == "raycheck render: interrupted\n"
    assert list(tmp_path.iterdir()) == []


def kill_self(signum: int) -> None:
    os.kill(os.getpid(), signum)
    time.sleep(5)  # the handler raises within this


@pytest.mark.parametrize("signum, status, word", [(signal.SIGINT, 130, "interrupted"),
                                                  (signal.SIGTERM, 143, "terminated")])
def test_a_signal_ends_the_action_with_its_status_and_one_line(signum, status, word, capsys):
    assert interruptible("prog", lambda: kill_self(signum) or 0) == status
    assert capsys.readouterr().err == f"prog: {word}\n"


def test_sigterm_made_a_plain_keyboard_interrupt_on_the_way_still_says_terminated(capsys):
    """An extension that re-raises the interrupt of the code it runs may raise a new
    KeyboardInterrupt for the Terminated that SIGTERM raised: the status is still SIGTERM's."""
    def action() -> int:
        try:
            kill_self(signal.SIGTERM)
        except Terminated:
            raise KeyboardInterrupt() from None
        return 0

    assert interruptible("prog", action) == 143
    assert capsys.readouterr().err == "prog: terminated\n"
    assert interruptible("prog", lambda: kill_self(signal.SIGINT) or 0) == 130  # not kept


def test_an_interrupt_a_c_extension_turned_into_its_own_error_still_ends_the_command(capsys):
    """numpy's C core, interrupted while it imports `datetime`, raises an ImportError that
    holds no trace of the interrupt (seen once in a cold check terminated 0.05 s in): the
    command still ends as terminated, in one line, not with the ImportError's traceback."""
    def action() -> int:
        try:
            kill_self(signal.SIGTERM)
        except Terminated:
            pass
        raise ImportError('PyCapsule_Import could not import module "datetime"')

    assert interruptible("prog", action) == 143
    assert capsys.readouterr().err == "prog: terminated\n"
    with pytest.raises(ImportError):  # an error with no interrupt before it is the error
        interruptible("prog", lambda: (_ for _ in ()).throw(ImportError("no module x")))


def c_prints_error(error: BaseException) -> None:
    """What numpy's import_array does with the error that stopped its import: PyErr_Print,
    here as PyRun_SimpleString calls it for the error its code raised."""
    main = sys.modules["__main__"]
    main.c_error = error
    try:
        assert ctypes.pythonapi.PyRun_SimpleString(b"raise c_error") == -1
    finally:
        del main.c_error


@pytest.mark.parametrize("swallowed", [False, True])
def test_an_interrupt_a_c_extension_printed_is_not_printed(swallowed, capsys):
    """numpy's import_array, interrupted inside (a cold check terminated while numpy loaded),
    prints the Terminated through PyErr_Print, or the ImportError it made of it, then raises an
    ImportError of its own: one line, no traceback. An error printed before any interrupt is
    still printed."""
    def action() -> int:
        try:
            kill_self(signal.SIGTERM)
        except Terminated as e:
            c_prints_error(ImportError("_multiarray_umath failed to import") if swallowed else e)
        raise ImportError("numpy.core.multiarray failed to import")

    assert interruptible("prog", action) == 143
    assert capsys.readouterr().err == "prog: terminated\n"

    def no_interrupt() -> int:
        c_prints_error(ImportError("_multiarray_umath failed to import"))
        return 0

    assert interruptible("prog", no_interrupt) == 0
    assert capsys.readouterr().err.endswith("\nImportError: _multiarray_umath failed to import\n")


def test_a_second_signal_lets_the_first_ones_cleanup_end(capsys):
    steps = []

    def action() -> int:
        try:
            kill_self(signal.SIGINT)
        finally:
            os.kill(os.getpid(), signal.SIGTERM)  # a second signal in the cleanup: ignored
            time.sleep(0.05)
            steps.append("cleaned up")
        return 0

    assert run_command("prog", action) == 130
    assert steps == ["cleaned up"]
    assert capsys.readouterr().err == "prog: interrupted\n"


def test_a_deferred_signal_is_raised_when_its_block_ends(capsys):
    steps = []

    def action() -> int:
        with signals_deferred():
            os.kill(os.getpid(), signal.SIGTERM)
            time.sleep(0.05)
            steps.append("second rename")
        steps.append("after")
        return 0

    assert interruptible("prog", action) == 143
    assert steps == ["second rename"]
    assert capsys.readouterr().err == "prog: terminated\n"


def test_the_interrupt_is_found_behind_the_errors_it_caused():
    """An interrupt while a C extension is imported comes out as its SystemError, with the
    interrupt as the context; Dr.Jit's wrappers keep it as their cause."""
    interrupt = Terminated()
    try:
        try:
            raise interrupt
        except KeyboardInterrupt:
            raise SystemError("returned a result with an exception set")
    except SystemError as e:
        imported = e
    wrapped = RuntimeError("record(): error encountered while recording (see above).")
    wrapped.__cause__ = RuntimeError("dr.if_stmt(): encountered an exception (see above).")
    wrapped.__cause__.__cause__ = imported
    assert interrupt_in(wrapped) is interrupt
    assert interrupt_in(RuntimeError("no interrupt")) is None


@pytest.mark.parametrize("interrupt", [KeyboardInterrupt(), Terminated()])
def test_traced_errors_give_up_the_interrupt_behind_them(interrupt):
    """A signal inside compile() while dr.syntax converts a loop (the first render's moments)
    comes out of Dr.Jit as "could not be compiled" caused by the interrupt, wrapped once more
    by the frozen function's recording: what leaves the block is the interrupt itself."""
    from raycheck.tracer.kernel.backend import traced_errors_unwrapped

    with pytest.raises(type(interrupt)) as raised:
        with traced_errors_unwrapped():
            try:
                try:
                    raise interrupt
                except KeyboardInterrupt as e:
                    raise RuntimeError("The following transformed AST generated by "
                                       "@drjit.syntax could not be compiled: ...") from e
            except RuntimeError as e:
                raise RuntimeError("record(): error encountered while recording a frozen "
                                   "function (see above).") from e
    assert raised.value is interrupt


def test_a_traced_error_keeps_its_own_cause():
    from raycheck.tracer.kernel.backend import traced_errors_unwrapped

    cause = OSError("disk full")
    with pytest.raises(ValueError) as raised:
        with traced_errors_unwrapped():
            try:
                try:
                    raise ValueError("bad value") from cause
                except ValueError as e:
                    raise RuntimeError("dr.if_stmt(): encountered an exception (see above).") \
                        from e
            except RuntimeError as e:
                raise RuntimeError("record(): error encountered (see above).") from e
    assert str(raised.value) == "bad value" and raised.value.__cause__ is cause


def test_an_interrupt_that_lands_in_a_finalizer_is_raised_after_it(capsys):
    """Python cannot raise an exception out of a __del__ method or a weakref callback (it
    prints "Exception ignored in ..." and goes on): an interrupt that lands there is raised at
    the next point that can."""
    steps = []

    class Finalized:
        def __del__(self):
            os.kill(os.getpid(), signal.SIGINT)
            time.sleep(0.05)  # the handler runs here, inside __del__
            steps.append("finalized")

    def action() -> int:
        Finalized()
        kill_self_later = time.monotonic() + 5
        while time.monotonic() < kill_self_later:
            time.sleep(0.01)
        steps.append("went on")
        return 0

    assert interruptible("prog", action) == 130
    assert steps == []
    assert capsys.readouterr().err == "prog: interrupted\n"


class SignalledWhenFinalized:
    def __del__(self):
        os.kill(os.getpid(), signal.SIGINT)
        time.sleep(0.05)  # the handler runs here, inside __del__


def test_a_second_signal_while_the_finalizer_hook_resends_the_first_is_ignored(monkeypatch,
                                                                               capsys):
    """The hook that raises a finalizer's interrupt again starts a thread, and starting one
    waits: a second signal arriving there (a pool worker gets SIGTERM from its group and from
    its parent) must not be raised inside the hook, where Python would print it as "Exception
    ignored in sys.unraisablehook" and lose it."""
    class SignalledWhileStarting(threading.Timer):
        def start(self) -> None:
            os.kill(os.getpid(), signal.SIGINT)
            time.sleep(0.05)  # the handler runs here, inside the hook
            super().start()

    monkeypatch.setattr(threading, "Timer", SignalledWhileStarting)

    def action() -> int:
        SignalledWhenFinalized()
        time.sleep(5)
        return 0

    assert interruptible("prog", action) == 130
    assert capsys.readouterr().err == "prog: interrupted\n"


def test_an_interrupt_that_lands_in_a_semaphores_finalizer_lets_it_end(monkeypatch, capsys):
    """A SIGTERM that landed between a pool's semaphore being unlinked and being unregistered
    (multiprocessing's finalizer, as the pool is freed) left the resource tracker to print two
    warnings after "terminated": the finalizer runs to its end and the interrupt follows."""
    import multiprocessing
    import multiprocessing.resource_tracker as tracker
    import multiprocessing.synchronize as synchronize

    registered, unregistered = [], []
    monkeypatch.setattr(tracker, "register", lambda name, _kind: registered.append(name))
    monkeypatch.setattr(tracker, "unregister", lambda name, _kind: unregistered.append(name))
    unlink = synchronize.sem_unlink

    def unlink_then_signalled(name: str) -> None:
        unlink(name)
        os.kill(os.getpid(), signal.SIGTERM)
        time.sleep(0.05)  # the handler runs here, inside the finalizer

    monkeypatch.setattr(synchronize, "sem_unlink", unlink_then_signalled)

    def action() -> int:
        lock = multiprocessing.get_context("spawn").Lock()
        del lock
        time.sleep(5)
        return 0

    assert interruptible("prog", action) == 143
    assert capsys.readouterr().err == "prog: terminated\n"
    assert len(registered) == 1
    assert unregistered == registered


def swallow_sigterm() -> None:
    """What ElementTree's `from _elementtree import *` under `except ImportError` does with an
    interrupt that lands in the C module's import of pyexpat: PyCapsule_Import makes it an
    ImportError, which is dropped, and the work goes on."""
    try:
        try:
            kill_self(signal.SIGTERM)
        except Terminated:
            raise ImportError('PyCapsule_Import could not import module "pyexpat"') from None
    except ImportError:
        pass


def test_a_swallowed_interrupt_is_raised_before_files_are_renamed_into_place(tmp_path, capsys):
    old = tmp_path / "a.png"
    old.write_bytes(b"old")

    def action() -> int:
        swallow_sigterm()
        write_all([(old, lambda tmp: Path(tmp).write_bytes(b"new"))])
        return 0

    assert interruptible("prog", action) == 143
    assert capsys.readouterr().err == "prog: terminated\n"
    assert [p.name for p in tmp_path.iterdir()] == ["a.png"] and old.read_bytes() == b"old"


def test_a_swallowed_interrupt_is_raised_before_a_folder_is_swapped_in(tmp_path, capsys):
    final = tmp_path / "out"
    final.mkdir()
    (final / "old").write_text("old")

    def action() -> int:
        with ReplacedFolder(final, finishes_run=True) as staging:
            (staging / "new").write_text("new")
            swallow_sigterm()
        return 0

    assert interruptible("prog", action) == 143
    assert capsys.readouterr().err == "prog: terminated\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == [".out.lock", "out"]
    assert [p.name for p in final.iterdir()] == ["old"]


def test_a_finalizers_interrupt_raised_again_before_its_resend_is_raised_once(capsys):
    """The hook sends a finalizer's interrupt again RESEND_S later; where a commit point raised
    it first, the resend is dropped: no second interrupt lands in the first one's cleanup."""
    steps = []

    def action() -> int:
        SignalledWhenFinalized()
        try:
            raise_swallowed()
        finally:
            time.sleep(0.2)  # a cleanup: the resend would land here
            steps.append("cleaned up")
        return 0

    assert interruptible("prog", action) == 130
    assert steps == ["cleaned up"]
    assert capsys.readouterr().err == "prog: interrupted\n"
