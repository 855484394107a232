"""Where cases run: a `concurrent.futures.Executor` chosen by -j / --scheduler.

    -j 1               in this process, one case after another (no worker start-up cost)
    -j N               a local pool of N 'spawn' processes (Mitsuba and Dr.Jit do not survive
                       fork: their thread pools and JIT state would be copied half-alive)
    --scheduler ADDR   the workers of a Dask distributed cluster (Client.get_executor())

Each worker process renders with `threads` Dr.Jit threads so that workers x threads does not
exceed the cores (N workers each using every core would thrash). The count travels with each
task (set once per process before its first kernel, see use_threads) rather than in a pool
initializer, because Dask workers have no initializer and may join a cluster later.
"""
from __future__ import annotations

import multiprocessing
import os
import signal
import sys
import threading
import time
from concurrent.futures import Executor, Future, ProcessPoolExecutor
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Callable, Iterator

from raycheck.tracer.process import (
    Terminated,
    exit_status,
    interrupt_in,
    raise_interrupt,
    reraising_hook,
    signals_deferred,
)

STOP_GRACE_S = 5.0  # a stopped worker's time to unwind its case before SIGKILL
_STOP_SIGNALS = {signal.SIGINT, signal.SIGTERM}


class InlineExecutor(Executor):
    """Runs each call at submit, in this process: -j 1, as the harness always did."""

    def submit(self, fn: Callable, /, *args, **kwargs) -> Future:
        future: Future = Future()
        try:
            future.set_result(fn(*args, **kwargs))
        except Exception as e:  # noqa: BLE001 - delivered through the future, as a pool does
            future.set_exception(e)
        return future


@dataclass(frozen=True)
class Workers:
    """An executor, how many cases it runs at once, and the Dr.Jit thread count its workers
    should use (None: leave it)."""

    executor: Executor
    slots: int
    threads: int | None


_threads_set: int | None = None


def use_threads(threads: int | None) -> None:
    """Sets this process's Dr.Jit thread count once (a worker's first task, before any
    kernel of it runs); None leaves Dr.Jit's default (every core)."""
    global _threads_set
    if threads is None or _threads_set == threads:
        return
    from raycheck.tracer.kernel.backend import import_drjit

    import_drjit().set_thread_count(threads)
    _threads_set = threads


def _worker_signals() -> None:
    """A pool worker's signals. Ctrl-C reaches the whole process group: the parent answers it
    (cancels what is queued, stops the workers, says "interrupted" once); workers dying of it
    mid-wait would each print a traceback. The parent stops a worker with SIGTERM: a case
    under way unwinds (its renderer's process group killed, its temporary folders removed)
    and the worker exits; an idle one exits at once."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, _stop_worker)
    sys.unraisablehook = reraising_hook(sys.unraisablehook)
    signal.pthread_sigmask(signal.SIG_UNBLOCK, _STOP_SIGNALS)  # blocked since the spawn (submit)


_case_running = False  # in a pool worker: whether _worker_case is running a case


def _stop_worker(signum: int, frame) -> None:
    if not _case_running:
        os._exit(exit_status(Terminated()))
    raise_interrupt(signum, frame)  # in a case: once it is past a signals_deferred block


def _worker_case(fn: Callable, *args):
    """fn(*args) in a pool worker, which SIGTERM stops once the case has unwound."""
    global _case_running
    try:
        _case_running = True
        return fn(*args)
    except BaseException as e:
        if interrupt_in(e) is not None:
            os._exit(exit_status(Terminated()))
        raise
    finally:
        _case_running = False


class WorkerPool(ProcessPoolExecutor):
    """A local pool of 'spawn' processes (-j N) that an interrupt stops at once (stop)."""

    def __init__(self, jobs: int) -> None:
        super().__init__(jobs, mp_context=multiprocessing.get_context("spawn"),
                         initializer=_worker_signals)

    def submit(self, fn: Callable, /, *args, **kwargs) -> Future:
        # the workers this may start are spawned with SIGINT and SIGTERM blocked, which they
        # keep until _worker_signals has set their handlers: a terminal's Ctrl-C reaches the
        # whole process group, and a worker still starting up would die of it with a traceback
        # (and an interrupt of this process waits until the spawn has sent the worker what it
        # starts from: a worker whose pipe closes halfway dies of EOFError with a traceback)
        mask = signal.pthread_sigmask(signal.SIG_BLOCK, _STOP_SIGNALS)
        try:
            with signals_deferred():
                return super().submit(_worker_case, fn, *args, **kwargs)
        finally:
            signal.pthread_sigmask(signal.SIG_SETMASK, mask)

    def stop(self) -> None:
        """Cancels the queued cases and stops the running ones: SIGTERM to each worker, SIGKILL
        to any still alive STOP_GRACE_S later (one busy in a long compilation: a worker that
        runs a candidate program answers SIGTERM at once, so no program is left behind).
        Waits for the pool's manager thread too: it closes its wake-up pipe as it ends, and
        Python's exit hook writes to that pipe, so a thread still ending at exit would make the
        write fail with a traceback after "interrupted" (CPython does not lock the two)."""
        processes = list((self._processes or {}).values())  # CPython's pool keeps them there
        # ... and its manager thread there (typeshed calls it the wake-up, which it is not)
        manager: threading.Thread | None = self._executor_manager_thread  # type: ignore[assignment]
        self.shutdown(wait=False, cancel_futures=True)
        for process in processes:
            process.terminate()
        deadline = time.monotonic() + STOP_GRACE_S
        for process in processes:
            process.join(max(0.0, deadline - time.monotonic()))
            if process.is_alive():
                process.kill()
                process.join()
        if manager is not None:
            manager.join(STOP_GRACE_S)


@contextmanager
def workers(jobs: int | None = None, scheduler: str | None = None) -> Iterator[Workers]:
    """The executor for -j JOBS (default: the number of cores) or --scheduler ADDRESS, shut
    down when the block ends; on an exception (Ctrl-C) the local pool's queued cases are
    cancelled and its running ones stopped (WorkerPool.stop) instead of waited for."""
    if scheduler is not None:
        with _dask(scheduler) as w:
            yield w
        return
    jobs = jobs or os.cpu_count() or 1
    if jobs == 1:
        yield Workers(InlineExecutor(), 1, None)
        return
    pool = WorkerPool(jobs)
    try:
        yield Workers(pool, jobs, max(1, (os.cpu_count() or 1) // jobs))
    except BaseException:
        pool.stop()
        raise
    pool.shutdown(wait=True)


class SchedulerError(OSError):
    """The Dask scheduler cannot be reached."""


@contextmanager
def _dask(address: str) -> Iterator[Workers]:
    import logging

    from distributed import Client

    # what goes wrong is raised to us; the client's own warnings would follow the command's
    # one line
    logging.getLogger("distributed").setLevel(logging.ERROR)
    client = None
    try:
        try:
            client = Client(address, timeout=10, set_as_default=False)
        except (OSError, ValueError, TypeError) as e:
            raise SchedulerError(f"--scheduler {address}: cannot connect ({e})") from None
        slots, threads = dask_slots(client)
        yield Workers(client.get_executor(), slots, threads)
    except BaseException as e:
        if interrupt_in(e) is not None:  # connections cut halfway log errors as they close
            logging.disable(logging.CRITICAL)
            _close_unnamed_clients(e, client)
        raise
    finally:
        if client is not None:
            client.close()


def _close_unnamed_clients(interrupt: BaseException, named) -> None:
    """Closes the client that `interrupt` caught in its constructor (no variable holds it:
    only the interrupt's traceback). Left to its `__del__`, it would close when the garbage
    collector finds it, at the interpreter's exit after its event loop has closed, and print a
    traceback ("IOLoop is closed") after the command's one line. One that cannot close now is
    marked closed, so that its `__del__` does nothing."""
    import traceback

    from distributed import Client

    for frame, _ in traceback.walk_tb(interrupt.__traceback__):
        other = frame.f_locals.get("self")
        if not isinstance(other, Client) or other is named:
            continue
        try:
            other.close(timeout=2)
        except Exception:  # noqa: BLE001 - its connection was cut halfway: nothing to close
            other.status = "closed"


def dask_slots(client) -> tuple[int, int]:
    """The cluster's task slots (workers x threads per worker) and the Dr.Jit threads per
    slot: on each host its cores over the slots there; the smallest over hosts, so no host is
    oversubscribed."""
    info = client.scheduler_info(n_workers=-1)["workers"]
    cores = client.run(os.cpu_count)  # worker address -> its host's cores
    slots: dict[str, int] = {}
    host_cores: dict[str, int] = {}
    for address, worker in info.items():
        host = worker["host"]
        slots[host] = slots.get(host, 0) + worker["nthreads"]
        host_cores[host] = cores.get(address) or 1
    threads = min((max(1, host_cores[h] // slots[h]) for h in slots), default=1)
    return max(1, sum(slots.values())), threads
