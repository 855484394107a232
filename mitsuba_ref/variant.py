"""Loading Mitsuba once, with a usable libLLVM, in the chosen variant, with our plugins registered.

Dr.Jit's CPU backend loads the system libLLVM at run time and aborts the whole process (not a
Python exception) with LLVM 15/16, so a libLLVM >= 17 is pinned through DRJIT_LIBLLVM_PATH before
drjit is first imported. The library is the one the tracer pins
(`tracer.kernel.backend.find_libllvm`:
the Dr.Jit/LLVM setup is, with the parser, all the two renderers share, DESIGN.md), so that one
process running both loads one libLLVM whichever imports drjit first.

Plugin classes subclass variant-specific types (`mi.Sensor`, `mi.BSDF`, ...), which only exist once
a variant is set; `use()` sets the variant and (re)imports the plugin modules so that their
classes bind to it and register themselves under it.
"""
from __future__ import annotations

import importlib
import sys
from types import ModuleType

from raycheck.tracer.kernel.backend import BackendError, pin_libllvm
from raycheck.tracer.process import signals_deferred

DEFAULT_VARIANT = "llvm_ad_rgb"
# The variants the reference supports, by the names users may give (--variant / --backend).
VARIANTS = {"llvm": "llvm_ad_rgb", "llvm_ad_rgb": "llvm_ad_rgb",
            "cuda": "cuda_ad_rgb", "cuda_ad_rgb": "cuda_ad_rgb"}
PLUGIN_MODULES = ("raycheck.mitsuba_ref.camera", "raycheck.mitsuba_ref.bsdf",
                  "raycheck.mitsuba_ref.integrator")

_registered: dict[str, bool] = {}  # variants whose plugins are registered in this process


class VariantError(RuntimeError):
    """The requested Mitsuba variant cannot be used on this machine (one-line message)."""


def pin_llvm() -> None:
    """Point Dr.Jit at a libLLVM >= 17 unless drjit is already loaded or the user chose one."""
    if "drjit" in sys.modules:
        return  # too late to change, and whoever imported it pinned it (the tracer does)
    try:
        pin_libllvm()
    except BackendError as e:
        raise VariantError(str(e)) from None


def _import_mitsuba() -> ModuleType:
    pin_llvm()
    with signals_deferred():  # see backend.import_drjit
        import drjit as dr
        import mitsuba as mi

    # The course renderer is plain IEEE float32 C++: no reassociation or contraction in the JIT
    # code we trace (the camera formula, shading sums, cube-map blend). This is the same global
    # setting the tracer uses, so one process running both renderers sees one consistent flag.
    dr.set_flag(dr.JitFlag.FastMath, False)
    return mi


def use(variant: str = DEFAULT_VARIANT) -> ModuleType:
    """Set the Mitsuba variant (llvm_ad_rgb or cuda_ad_rgb) and register our plugins for it."""
    if variant not in VARIANTS:
        raise VariantError(f"unknown variant '{variant}' (expected llvm_ad_rgb or cuda_ad_rgb)")
    name = VARIANTS[variant]
    mi = _import_mitsuba()
    if name == "cuda_ad_rgb":
        import drjit as dr
        if not dr.has_backend(dr.JitBackend.CUDA):
            raise VariantError("the cuda_ad_rgb variant needs a CUDA GPU and driver; none found")
    if mi.variant() != name or not _registered.get(name):
        with signals_deferred():  # the variant's native modules load here
            try:
                mi.set_variant(name)
            except (ImportError, AttributeError, RuntimeError) as e:
                raise VariantError(f"cannot use Mitsuba variant {name}: {e}") from None
            # Mitsuba's warnings (e.g. about float precision in extreme scenes) would
            # interleave with our one-line messages; errors still surface as exceptions
            mi.set_log_level(mi.LogLevel.Error)
            for mod in PLUGIN_MODULES:
                if mod in sys.modules:
                    importlib.reload(sys.modules[mod])
                else:
                    importlib.import_module(mod)
            _registered[name] = True
    return mi


def ensure() -> ModuleType:
    """Mitsuba with our plugins registered: keeps the current variant if it is one of ours,
    otherwise sets the default."""
    mi = _import_mitsuba()
    current = mi.variant()
    return use(current if current in VARIANTS.values() else DEFAULT_VARIANT)
