"""The acceleration structures' builders, their results kept for the inputs they were last
given: a cause search renders one scene a few hundred times, each render with a Renderer of its
own, and the same triangles get the same BVH, octrees, shadow grids and screen tiles. Inputs
are compared by content (arrays by their bytes), and with them the settings of the builder's
module, so a result is reused only where the builder would have made the same one; results are
made read only, as they are shared from then on."""
from __future__ import annotations

import dataclasses
import functools
import hashlib
import threading
from collections import OrderedDict
from typing import Any, Callable, TypeVar

import numpy as np

F = TypeVar("F", bound=Callable[..., Any])


def kept(count: int) -> Callable[[F], F]:
    """A builder whose results for its last `count` distinct inputs are kept."""

    def decorate(build: F) -> F:
        results: OrderedDict[bytes, Any] = OrderedDict()
        lock = threading.Lock()

        @functools.wraps(build)
        def remembered(*args, **kwargs):
            key = fingerprint((args, sorted(kwargs.items()), _settings(build)))
            with lock:
                if key in results:
                    results.move_to_end(key)
                    return results[key]
            result = build(*args, **kwargs)
            _freeze(result)
            with lock:
                results[key] = result
                while len(results) > count:
                    results.popitem(last=False)
            return result

        return remembered  # type: ignore[return-value]

    return decorate


def _settings(build: Callable) -> list[tuple[str, Any]]:
    """The numbers in upper case of `build`'s module (its limits and sizes), as they are now:
    part of the key, so that a result made under other settings (a test's) is not reused."""
    return sorted((name, value) for name, value in build.__globals__.items()
                  if name.isupper() and isinstance(value, (int, float)))


def fingerprint(value: Any) -> bytes:
    """A digest of `value`'s content: arrays (shape, type and bytes), dataclasses (type and
    fields), sequences, dicts and scalars. Anything else is refused: compared by identity it
    would be reused for other content."""
    digest = hashlib.blake2b(digest_size=20)
    _feed(digest, value)
    return digest.digest()


def _feed(digest, value: Any) -> None:
    if isinstance(value, np.ndarray):
        digest.update(f"a{value.shape}{value.dtype.str}".encode())
        digest.update(np.ascontiguousarray(value).view(np.uint8).ravel())
    elif isinstance(value, (bool, int, float, str, type(None))):
        # repr keeps -0.0 apart from 0.0 and the type apart (1 from 1.0 and True)
        digest.update(f"{type(value).__name__}:{value!r};".encode())
    elif isinstance(value, (np.floating, np.integer, np.bool_)):
        digest.update(f"{value.dtype.str}:{value.item()!r};".encode())
    elif dataclasses.is_dataclass(value) and not isinstance(value, type):
        digest.update(f"d{type(value).__qualname__}(".encode())
        for f in dataclasses.fields(value):
            _feed(digest, getattr(value, f.name))
        digest.update(b")")
    elif isinstance(value, (list, tuple)):
        digest.update(f"s{len(value)}(".encode())
        for item in value:
            _feed(digest, item)
        digest.update(b")")
    elif isinstance(value, dict):
        _feed(digest, sorted(value.items()))
    else:
        raise TypeError(f"no content fingerprint for a {type(value).__name__}")


def _freeze(value: Any) -> None:
    """Every array reachable from `value` (as _feed walks it) made read only."""
    if isinstance(value, np.ndarray):
        value.setflags(write=False)
    elif dataclasses.is_dataclass(value) and not isinstance(value, type):
        for f in dataclasses.fields(value):
            _freeze(getattr(value, f.name))
    elif isinstance(value, (list, tuple)):
        for item in value:
            _freeze(item)
    elif isinstance(value, dict):
        for item in value.values():
            _freeze(item)
