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
from concurrent.futures import Executor, Future, ProcessPoolExecutor
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Callable, Iterator


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
    from raycheck.tracer.backend import import_drjit

    import_drjit().set_thread_count(threads)
    _threads_set = threads


def _leave_ctrl_c_to_the_parent() -> None:
    # Ctrl-C reaches the whole process group: the parent cancels what is queued and reports
    # "interrupted" once; workers dying of it mid-wait would each print a traceback
    signal.signal(signal.SIGINT, signal.SIG_IGN)


@contextmanager
def workers(jobs: int | None = None, scheduler: str | None = None) -> Iterator[Workers]:
    """The executor for -j JOBS (default: the number of cores) or --scheduler ADDRESS, shut
    down when the block ends; on an exception (Ctrl-C) queued cases are cancelled instead of
    waited for."""
    if scheduler is not None:
        with _dask(scheduler) as w:
            yield w
        return
    jobs = jobs or os.cpu_count() or 1
    if jobs == 1:
        yield Workers(InlineExecutor(), 1, None)
        return
    pool = ProcessPoolExecutor(jobs, mp_context=multiprocessing.get_context("spawn"),
                               initializer=_leave_ctrl_c_to_the_parent)
    try:
        yield Workers(pool, jobs, max(1, (os.cpu_count() or 1) // jobs))
    except BaseException:
        pool.shutdown(wait=False, cancel_futures=True)
        raise
    pool.shutdown(wait=True)


class SchedulerError(OSError):
    """The Dask scheduler cannot be reached."""


@contextmanager
def _dask(address: str) -> Iterator[Workers]:
    from distributed import Client

    try:
        client = Client(address, timeout=10)
    except (OSError, ValueError, TypeError) as e:
        raise SchedulerError(f"--scheduler {address}: cannot connect ({e})") from None
    try:
        slots, threads = dask_slots(client)
        yield Workers(client.get_executor(), slots, threads)
    finally:
        client.close()


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
