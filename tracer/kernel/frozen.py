"""What a Renderer needs to replay its launches with dr.freeze instead of tracing them again
(Renderer.render): the Dr.Jit arrays and the plain values its kernels are made from, which
dr.freeze takes as inputs (a launch may use no array made before the recording that is not
one), and a pause of the garbage collector around each recording.
"""
from __future__ import annotations

import contextlib
import dataclasses
import gc
import threading
from types import ModuleType

from .backend import import_drjit, traced_errors_unwrapped


def call_frozen(frozen, *args):
    """frozen(*args) with the collector paused (gc_paused), and an error raised while the
    launch was traced for its recording raised as itself (backend.traced_errors_unwrapped)."""
    with traced_errors_unwrapped(), gc_paused():
        return frozen(*args)


_pause_lock = threading.Lock()
_pauses = 0  # gc_paused blocks open, over all threads (a Dask worker runs cases in threads)
_collector_was_enabled = False


@contextlib.contextmanager
def gc_paused():
    """No cyclic garbage collection inside. Dr.Jit 1.5 aborts the process ("enqueue_host_func():
    this function cannot be recorded") when the collector frees garbage of earlier renders (a
    renderer left in a reference cycle) while a frozen launch is recorded: seen in long-lived
    processes (pytest workers, the harness), test_frozen_renders reproduces it. The collector
    is global: it runs again only when the last open block of any thread closes."""
    global _pauses, _collector_was_enabled
    with _pause_lock:
        if _pauses == 0:
            _collector_was_enabled = gc.isenabled()
            gc.disable()
        _pauses += 1
    try:
        yield
    finally:
        with _pause_lock:
            _pauses -= 1
            if _pauses == 0 and _collector_was_enabled:
                gc.enable()


def plain_state(obj, skip: tuple[str, ...] = ()) -> str:
    """obj's attributes (but those named in skip) that hold plain values, by name: numbers,
    strings, and tuples and frozen dataclasses of plain values (a Renderer's options), as
    one string (dr.freeze compares a string as a whole; a change of a boolean field of a
    dataclass in its inputs went unnoticed)."""
    def plain(v) -> bool:
        if isinstance(v, tuple):
            return all(plain(x) for x in v)
        if dataclasses.is_dataclass(v) and not isinstance(v, type):
            # typeshed's DataclassInstance declares __dataclass_fields__ only
            return v.__dataclass_params__.frozen and all(  # type: ignore[attr-defined]
                plain(getattr(v, f.name)) for f in dataclasses.fields(v))
        return v is None or isinstance(v, (bool, int, float, str))

    return repr(sorted((k, v) for k, v in vars(obj).items() if k not in skip and plain(v)))


def jit_state(root) -> list:
    """Every Dr.Jit array reachable from root's attributes, through lists, tuples, dicts and
    the attributes of objects of Python classes (not those of Dr.Jit, numpy or the standard
    library's modules and functions)."""
    dr = import_drjit()
    found, seen, todo = [], set(), [root]
    while todo:
        obj = todo.pop()
        if id(obj) in seen:
            continue
        seen.add(id(obj))
        if dr.is_array_v(obj):
            found.append(obj)
        elif isinstance(obj, (list, tuple)):
            todo.extend(obj)
        elif isinstance(obj, dict):
            todo.extend(obj.values())
        elif (hasattr(obj, "__dict__") and not isinstance(obj, (type, ModuleType))
              and not callable(obj)
              and type(obj).__module__.split(".")[0] not in ("drjit", "numpy", "builtins")):
            todo.extend(vars(obj).values())
    return found
