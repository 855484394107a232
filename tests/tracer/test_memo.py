"""The builders' memo (accel/memo.py): a result is reused only for inputs of the same content,
and is shared read only."""
from __future__ import annotations

import sys
from dataclasses import dataclass

import numpy as np
import pytest

from raycheck.tracer.accel.memo import fingerprint, kept


@dataclass(frozen=True)
class Box:
    lo: np.ndarray
    hi: np.ndarray


def test_fingerprints_tell_apart_what_a_builder_could_tell_apart():
    a = np.array([1.0, 2.0, 3.0], np.float32)
    same = [fingerprint(a), fingerprint(a.copy()), fingerprint(np.array([1, 2, 3], np.float32))]
    assert len(set(same)) == 1
    others = [a.astype(np.float64), a.reshape(3, 1), np.array([1.0, 2.0, -0.0], np.float32),
              np.array([1.0, 2.0, 3.0000002], np.float32), a[::-1].copy()]
    assert len({fingerprint(x) for x in [a, *others]}) == 1 + len(others)
    # scalars by type and sign; a dataclass by its type and fields
    assert len({fingerprint(x) for x in [0.0, -0.0, 0, False, None, "0"]}) == 6
    box = Box(a, a + 1)
    assert fingerprint(box) == fingerprint(Box(a.copy(), a + 1))
    assert fingerprint(box) != fingerprint((a, a + 1))
    assert fingerprint([a, 1]) != fingerprint([[a], 1])


def test_anything_else_is_refused_rather_than_compared_by_identity():
    with pytest.raises(TypeError, match="object"):
        fingerprint(object())


def test_kept_results_are_reused_for_equal_content_only_and_read_only():
    calls = []

    @kept(2)
    def build(points: np.ndarray, scale: float = 1.0) -> Box:
        calls.append(points.copy())
        return Box(points.min(axis=0) * scale, points.max(axis=0) * scale)

    p = np.arange(12, dtype=np.float32).reshape(4, 3)
    first = build(p)
    assert build(p.copy()) is first and len(calls) == 1
    assert build(p, scale=2.0) is not first and len(calls) == 2
    with pytest.raises(ValueError, match="read-only"):
        first.lo[0] = 5
    assert build(p) is first  # used last now: the input with scale 2 is the oldest
    build(p + 1)  # a third input: the oldest goes
    assert len(calls) == 3
    assert build(p) is first and len(calls) == 3
    build(p, scale=2.0)
    assert len(calls) == 4
    np.testing.assert_array_equal(first.hi, [9, 10, 11])


LIMIT = 10


@kept(4)
def _capped(points: np.ndarray) -> np.ndarray:
    return np.minimum(points, LIMIT)


def test_a_module_setting_is_part_of_the_key(monkeypatch):
    """A builder's module settings (upper-case numbers) as they are when it is called: a test
    that changes one gets a result made with it, not one kept from before."""
    p = np.array([5.0, 50.0])
    np.testing.assert_array_equal(_capped(p), [5, 10])
    monkeypatch.setattr(sys.modules[__name__], "LIMIT", 20)
    np.testing.assert_array_equal(_capped(p), [5, 20])
