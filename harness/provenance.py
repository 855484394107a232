"""Where a report's numbers came from: versions, machine, seeds, commit."""
from __future__ import annotations

import os
import platform
import subprocess
from pathlib import Path

from .catalog import REPO
from .renderers import ENGINE_PACKAGES
from .versions import package_version


def _git_commit() -> str:
    try:
        out = subprocess.run(["git", "rev-parse", "HEAD"], cwd=REPO, capture_output=True,
                             text=True, timeout=10)
        dirty = subprocess.run(["git", "status", "--porcelain"], cwd=REPO, capture_output=True,
                               text=True, timeout=10).stdout.strip()
        return out.stdout.strip() + (" (with uncommitted changes)" if dirty else "") \
            if out.returncode == 0 else "unknown"
    except (OSError, subprocess.SubprocessError):
        return "unknown"


def _cpu() -> str:
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown"


def vector_isa(cpuinfo: Path = Path("/proc/cpuinfo")) -> str:
    """The widest x86 vector instruction set this CPU has (avx512, avx2, avx, sse), else the
    machine's architecture. Mitsuba's renders depend on it (Embree and Dr.Jit's LLVM backend
    pick their kernels by it): a sample that grazes an edge can hit on one and miss on another,
    and a depth's last bit can differ. The tracer's renders do not depend on it."""
    try:
        words = next((line.split(":", 1)[1].split()
                      for line in cpuinfo.read_text().splitlines()
                      if line.startswith("flags")), [])
    except OSError:
        words = []
    flags = set(words)
    for isa, flag in (("avx512", "avx512f"), ("avx2", "avx2"), ("avx", "avx"), ("sse", "sse")):
        if flag in flags:
            return isa
    return platform.machine() or "unknown"


def provenance(seed: int | None = None) -> dict[str, str]:
    """Versions, machine and commit; the jitter seed where one was used."""
    from raycheck.tracer.kernel.backend import import_drjit, llvm_description

    dr = import_drjit()
    prov = {
        "raycheck": package_version("raycheck"),
        "git commit": _git_commit(),
        **{package: package_version(package) for package in ENGINE_PACKAGES},
        "llvm": llvm_description(),
        "python": platform.python_version(),
        "cpu": _cpu(),
        "vector isa": vector_isa(),
        "threads": str(dr.thread_count()) if hasattr(dr, "thread_count") else str(os.cpu_count()),
        "platform": platform.platform(),
    }
    if seed is not None:
        prov["seed"] = str(seed)
    return prov
