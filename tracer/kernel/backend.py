"""Loading Dr.Jit safely and picking the array namespace for a backend and precision.

Dr.Jit's CPU backend needs libLLVM >= 17 and aborts the whole process (not a Python exception)
on older ones, so the library is located and pinned before drjit is first imported.
"""
from __future__ import annotations

import contextlib
import functools
import glob
import os
import re
import sys
from types import ModuleType
from typing import TYPE_CHECKING, Any, Callable, NoReturn

from ..process import interrupt_in, signals_deferred

if TYPE_CHECKING:
    import numpy as np

MIN_LLVM = 17

_LLVM_DIRS = (
    "/usr/lib/x86_64-linux-gnu",
    "/usr/lib/aarch64-linux-gnu",
    "/usr/lib",
    "/usr/local/lib",
)


class BackendError(RuntimeError):
    """The requested backend cannot be used on this machine."""


def _llvm_version(path: str) -> int | None:
    m = re.search(r"libLLVM[-.]?(?:so\.)?(\d+)", os.path.basename(path))
    return int(m.group(1)) if m else None


def find_libllvm() -> str | None:
    """The newest libLLVM of version >= 17 on this machine, or None."""
    candidates: list[tuple[int, str]] = []
    patterns = ["libLLVM-*.so*", "libLLVM.so.*"]
    dirs = list(_LLVM_DIRS) + sorted(glob.glob("/usr/lib/llvm-*/lib"))
    for d in dirs:
        for pat in patterns:
            for path in glob.glob(os.path.join(d, pat)):
                v = _llvm_version(path)
                if v is not None and v >= MIN_LLVM:
                    candidates.append((v, path))
    if not candidates:
        return None
    return max(candidates)[1]


def pin_libllvm() -> None:
    """Points Dr.Jit (through DRJIT_LIBLLVM_PATH, read when drjit loads) at a libLLVM >= 17,
    unless the user chose one (BackendError: none, or the chosen one is missing)."""
    given = os.environ.get("DRJIT_LIBLLVM_PATH")
    if given:
        if not os.path.exists(given):
            raise BackendError(f"DRJIT_LIBLLVM_PATH={given} does not exist")
        return
    path = find_libllvm()
    if path is None:
        raise BackendError(
            f"Dr.Jit's CPU backend needs libLLVM {MIN_LLVM} or newer and none was found; "
            "install it with 'apt-get install libllvm19' (or run 'make install' as root), "
            "or set DRJIT_LIBLLVM_PATH to such a library"
        )
    os.environ["DRJIT_LIBLLVM_PATH"] = path


_drjit: ModuleType | None = None


def import_drjit() -> ModuleType:
    """Import drjit with a usable libLLVM pinned; exact float arithmetic (no FastMath)."""
    global _drjit
    if _drjit is None:
        if "drjit" not in sys.modules:
            pin_libllvm()
        # an interrupt inside the import aborts the process (Python code that Dr.Jit's native
        # module runs as it loads cannot pass an exception back), or leaves a module that
        # crashes the interpreter's exit or registers its types twice when imported again:
        # it is raised once the import is done
        with signals_deferred():
            import drjit as dr

        # The course renderer is plain IEEE float32 C++: no reassociation, no contraction.
        dr.set_flag(dr.JitFlag.FastMath, False)
        _drjit = dr
    return _drjit


@contextlib.contextmanager
def traced_errors_unwrapped():
    """An exception that code Dr.Jit traced inside the block raised comes out as itself. Dr.Jit
    re-raises it as an error of its own ("dr.if_stmt(): encountered an exception (see
    above).", "record(): error encountered while recording a frozen function (see above).")
    layer by layer, each keeping the one it wraps as its cause, which would hide a ValueError,
    a MemoryError or a Ctrl-C from those who handle them (a RuntimeError handler would take a
    Ctrl-C for a failed render). An interrupt behind any of them (also one that Dr.Jit's own
    errors name as their cause, such as dr.syntax's "could not be compiled" for a Ctrl-C
    inside compile()) comes out as the interrupt."""
    try:
        yield
    except (RuntimeError, TypeError) as e:
        original = e
        while original.__cause__ is not None and "(see above)" in str(original) and \
                type(original).__module__ == "builtins":
            original = original.__cause__
        interrupt = interrupt_in(original)
        if interrupt is not None and interrupt is not e:
            raise interrupt.with_traceback(interrupt.__traceback__) from None
        if original is e:
            raise
        # its own cause stays with it; only the wrappers' context is left out
        original.__suppress_context__ = True
        raise original.with_traceback(original.__traceback__)


def from_numpy(tp: Any, values: np.ndarray) -> Any:
    """tp(values), with kernels that do not depend on where numpy put `values`. Dr.Jit 1.5 reads
    an array made from numpy in numpy's own memory, and loads a size-1 one with `align 4` only
    where that memory is 64-byte aligned, else `align 1`: each process could then compile its
    own version of a kernel already in the cache. A size-1 array is made opaque from its
    Python scalar instead (Dr.Jit's memory, always aligned)."""
    flat = values.reshape(-1)
    if flat.size == 1:
        return import_drjit().opaque(tp, flat[0].item())
    return tp(flat)


ALIGN = 64  # bytes


def aligned_zeros(shape, dtype) -> np.ndarray:
    """Zeros in a buffer whose start is ALIGN-byte aligned. Dr.Jit arrays built from numpy use
    the numpy memory, and Dr.Jit 1.5 compiles a gather of 4 consecutive values into one packet
    load only when that memory is 64-byte aligned (else 4 scalar gathers, and another kernel);
    numpy itself only guarantees 16 bytes."""
    import numpy as np

    dtype = np.dtype(dtype)
    nbytes = int(np.prod(shape)) * dtype.itemsize
    buf = np.zeros(nbytes + ALIGN, np.uint8)
    start = (-buf.ctypes.data) % ALIGN
    return buf[start:start + nbytes].view(dtype).reshape(shape)


@contextlib.contextmanager
def recording_kernel():
    """The block records a render kernel with Dr.Jit's OptimizeLoops off. On, Dr.Jit 1.5.0
    records a symbolic loop's body twice (the first recording finds loop-invariant state) and
    keeps the first recording's writes to local memory allocated outside the loop: the mirror
    chain's per-level buffers (shading.Shader._mirror_chain) made the kernel run its whole
    body, shading and shadow rays included, twice per level (seen in the LLVM IR: a second
    copy in the loop's condition block; renders with -bounces took 1.4-1.7x as long). Off,
    each loop is recorded once and computes the same values. FastMath is set off here too:
    Dr.Jit's flags belong to a thread, and import_drjit set them in the importing thread
    only (a Dask worker renders cases in threads of its own)."""
    dr = import_drjit()
    with dr.scoped_set_flag(dr.JitFlag.OptimizeLoops, False), \
            dr.scoped_set_flag(dr.JitFlag.FastMath, False):
        yield


def syntax_on_first_call(fn: Callable) -> Callable:
    """dr.syntax(fn), applied when fn is first called rather than when its module is imported
    (renders of scenes without meshes never call the BVH and octree loops), and kept in the
    per-machine cache as Python keeps bytecode (_syntax_cached)."""
    converted: Callable | None = None

    @functools.wraps(fn)
    def call(*args, **kwargs):
        nonlocal converted
        if converted is None:
            converted = _syntax_cached(fn)
        return converted(*args, **kwargs)

    return call


def _syntax_cached(fn: Callable) -> Callable:
    """dr.syntax(fn), whose code (re-parsing, rewriting and compiling fn's source: ~20 ms for
    each of the BVH and octree loops, in every process that renders a mesh) is kept in the
    per-machine cache (cache.py) under a digest of fn's source file, name and line, the
    interpreter's bytecode version and Dr.Jit's; the function made from it is the one
    dr.syntax makes (that code with fn's globals and defaults)."""
    import hashlib
    import importlib.util
    import marshal
    import types
    from pathlib import Path

    from ..cache import cache_folder, load_bytes, save_bytes

    dr = import_drjit()
    code = fn.__code__
    try:
        source = Path(code.co_filename).read_bytes()
    except OSError:  # no source file: nothing to key the entry on (dr.syntax needs it anyway)
        return dr.syntax(fn)
    digest = hashlib.blake2b(digest_size=16)
    for part in (importlib.util.MAGIC_NUMBER, dr.__version__.encode(), fn.__qualname__.encode(),
                 str(code.co_firstlineno).encode(), source):
        digest.update(len(part).to_bytes(8, "little") + part)
    entry = cache_folder() / "syntax" / f"{digest.hexdigest()}.marshal"
    data = load_bytes(entry)
    try:
        cached = marshal.loads(data) if data is not None else None
    except (EOFError, ValueError, TypeError):  # a damaged entry: converted again
        cached = None
    if isinstance(cached, types.CodeType) and cached.co_name == code.co_name:
        converted = types.FunctionType(cached, fn.__globals__)
        converted.__defaults__ = fn.__defaults__
        return converted
    converted = dr.syntax(fn)
    save_bytes(entry, marshal.dumps(converted.__code__))
    return converted


def llvm_description() -> str:
    dr = import_drjit()
    try:
        major, minor, patch = dr.detail.llvm_version()
        return f"LLVM {major}.{minor}.{patch} ({os.environ.get('DRJIT_LIBLLVM_PATH', 'default')})"
    except Exception:  # noqa: BLE001 - only used for a provenance string
        return os.environ.get("DRJIT_LIBLLVM_PATH", "unknown LLVM")


def array_namespace(backend: str = "llvm", precision: str = "single") -> ModuleType:
    """The Dr.Jit module holding Float/Array3f/... types for backend and precision."""
    dr = import_drjit()
    ns: ModuleType
    if backend == "llvm":
        with signals_deferred():  # a native module, as in import_drjit
            import drjit.llvm as ns
    elif backend == "cuda":
        if not dr.has_backend(dr.JitBackend.CUDA):
            raise BackendError("the CUDA backend is not available on this machine (no GPU/driver)")
        with signals_deferred():
            import drjit.cuda as ns
    else:
        raise BackendError(f"unknown backend '{backend}' (expected llvm or cuda)")
    if precision not in ("single", "double"):
        raise BackendError(f"unknown precision '{precision}' (expected single or double)")
    return ns


def begin_render_process() -> None:
    """Settings for a process that only renders, made before numpy is imported: one OpenBLAS
    thread. The tracer does no BLAS work, and the threads OpenBLAS starts at numpy's import
    took ~45 ms of CPU there (~3 ms of wall time), on a loaded 2-core machine from the render."""
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")


def end_render_process(code: int) -> NoReturn:
    """Ends a process that only rendered, with exit status `code`, without Python's and
    Dr.Jit's teardown (freeing every variable, kernel and thread: ~40 ms of a 0.3 s render at
    800x800). Nothing is lost: the output files are complete and renamed, and Dr.Jit wrote
    each kernel to its cache when it compiled it."""
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (OSError, ValueError):  # a closed pipe or stream: nothing more can be said
            pass
    os._exit(code)
