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


def _configure_llvm() -> None:
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
            _configure_llvm()
        import drjit as dr

        # The course renderer is plain IEEE float32 C++: no reassociation, no contraction.
        dr.set_flag(dr.JitFlag.FastMath, False)
        _drjit = dr
    return _drjit


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
    """dr.syntax(fn), applied when fn is first called rather than when its module is imported:
    dr.syntax re-parses and compiles fn's source, which for the BVH and octree loops was about
    half of the tracer's own import time, and renders of scenes without meshes never call them."""
    converted: Callable | None = None

    @functools.wraps(fn)
    def call(*args, **kwargs):
        nonlocal converted
        if converted is None:
            converted = import_drjit().syntax(fn)
        return converted(*args, **kwargs)

    return call


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
    if backend == "llvm":
        import drjit.llvm as ns
    elif backend == "cuda":
        if not dr.has_backend(dr.JitBackend.CUDA):
            raise BackendError("the CUDA backend is not available on this machine (no GPU/driver)")
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
