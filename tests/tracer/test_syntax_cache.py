"""The tracer's loops as @dr.syntax compiles them, kept in the per-machine cache
(backend._syntax_cached): a cached entry gives the function dr.syntax gives, a damaged one is
made again, and an edited source file never gets its old code."""
from __future__ import annotations

import importlib.util
import marshal
from pathlib import Path

import pytest

from raycheck.tracer.kernel import backend
from raycheck.tracer.kernel.backend import import_drjit

# a module with a loop that only runs as dr.syntax rewrites it (a while over a Dr.Jit mask)
MODULE = '''
import drjit.llvm as llvm


def count(n, start=0):
    i = llvm.UInt32(start)
    while i < n:
        i += STEP
    return i
'''


def load(path: Path, step: int, name: str):
    """The module at path, written with the step `step`, imported as `name` (a step of
    another length makes a file of another size, which Python's bytecode cache notices)."""
    path.write_text(MODULE.replace("STEP", str(step)))
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture
def cache(tmp_path: Path, monkeypatch) -> Path:
    monkeypatch.setenv("RAYCHECK_CACHE", str(tmp_path / "cache"))
    return tmp_path / "cache" / "syntax"


def count(fn, n: int) -> list[int]:
    dr = import_drjit()
    return fn(dr.llvm.UInt32([n, 0, n + 1])).numpy().tolist()


def test_a_cached_entry_gives_dr_syntax_s_function_without_converting(tmp_path, cache,
                                                                      monkeypatch):
    dr = import_drjit()
    fn = load(tmp_path / "loops.py", 3, "loops_a").count
    first = backend._syntax_cached(fn)
    [entry] = cache.iterdir()
    assert first.__code__ == dr.syntax(fn).__code__  # equal code objects

    def refuse(f):
        raise AssertionError("converted again")

    monkeypatch.setattr(dr, "syntax", refuse)
    again = backend._syntax_cached(fn)
    assert again.__code__ == first.__code__ == marshal.loads(entry.read_bytes())
    assert again.__globals__ is fn.__globals__ and again.__defaults__ == (0,)
    assert count(again, 7) == count(first, 7) == [9, 0, 9]


def test_a_damaged_entry_is_made_again(tmp_path, cache):
    fn = load(tmp_path / "loops.py", 2, "loops_b").count
    backend._syntax_cached(fn)
    [entry] = cache.iterdir()
    good = entry.read_bytes()
    entry.write_bytes(good[:len(good) // 2])
    assert count(backend._syntax_cached(fn), 5) == [6, 0, 6]
    assert marshal.loads(entry.read_bytes()) == marshal.loads(good)


def test_an_edited_source_file_gets_new_code(tmp_path, cache):
    path = tmp_path / "loops.py"
    assert count(backend._syntax_cached(load(path, 1, "loops_c").count), 5) == [5, 0, 6]
    assert count(backend._syntax_cached(load(path, 10, "loops_d").count), 5) == [10, 0, 10]
    assert len(list(cache.iterdir())) == 2
