"""Primary-ray throughput of raycheck's BVH against brute force and Mitsuba/Embree, on
procedural meshes of growing size: the measurements, as rows of numbers (printed and shown as
tables by pages/throughput.py, never pass/fail).

For each mesh size, in one process and on the same rays:

* our BVH: host build time, node count, depth, memory; closest hit (``Intersector.closest``):
  t and triangle, what Mitsuba's preliminary intersection gives, cold (first launch: tracing,
  LLVM compile or kernel-cache load, run) and warm (the best of the following launches), and
  warm with the interpolated shading normal too, in M rays/s;
* brute force (small meshes only, on an evenly strided subset of the rays), checked to give
  exactly the BVH's hits;
* Mitsuba ``llvm_ad_rgb``: scene (Embree BVH) build time, ``ray_intersect_preliminary``
  (t and triangle, against ours) and ``ray_intersect`` (the full surface interaction, against
  ours with normals), warm, in M rays/s, and how often its hits agree with ours;
* a full render (primary rays, shading, shadow rays) through ``tracer.render.Renderer``, whose
  warm time against the triangle count is the scaling curve;
* JIT: kernels launched and their LLVM compile time in the cold launch, kernel-cache hits,
  and whether the closest-hit kernel got packet gathers (Dr.Jit 1.5 emits them only for
  64-byte aligned source memory, so this can change from one scene to the next).

Every timing ends with ``dr.eval(...)`` and ``dr.sync_thread()``. Warm closest-hit timings of
ours and Mitsuba's are taken in interleaved rounds, and the render scaling curve from
interleaved rounds over all sizes, so that load from other processes hits all alike; the build
reports its process CPU time beside the wall time for the same reason. ``fresh_cache=True``
runs the whole measurement in a child process whose HOME is an empty directory, so the on-disk
kernel cache (~/.drjit) starts empty and the first size's cold numbers include compilation.

The meshes, camera and rays: bench/throughput_inputs.py; both engines get the same rays.
"""
from __future__ import annotations

import contextlib
import dataclasses
import functools
import json
import math
import os
import re
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any, Callable

import numpy as np

from .records import JitCounts, ThroughputRow
from .throughput_inputs import bumpy_sphere, camera_rays, course_scene, flat_scene

SIZES = (1_000, 10_000, 100_000, 1_000_000)
RAYS = 1 << 20  # 1024 x 1024 primary rays
BRUTE_MAX_TRIANGLES = 10_000
BRUTE_RAY_WORK = 1 << 27  # ray-triangle tests per brute-force launch (rays = this / triangles)
WARM_RUNS = 3


def _closest(isect: Any, o: Any, d: Any, normals: bool = False) -> tuple:
    """One closest-hit launch of ours: what it is timed on (t and triangle, and the normal)."""
    h = isect.closest(o, d)
    return (h.t, h.order, h.normal) if normals else (h.t, h.order)


# --- timing helpers -----------------------------------------------------------------------------
class _Jit:
    """Kernel history of the launches since the last take()."""

    def __init__(self, dr) -> None:
        self.dr = dr
        dr.set_flag(dr.JitFlag.KernelHistory, True)
        dr.kernel_history()

    def take(self) -> JitCounts:
        h = [k for k in self.dr.kernel_history() if str(k.get("type", "")).endswith("JIT")]
        return JitCounts(
            kernels=len(h),
            compile_ms=sum(k.get("codegen_time", 0.0) + k.get("backend_time", 0.0)
                           for k in h if not (k.get("cache_hit") or k.get("cache_disk"))),
            cache_hits=sum(1 for k in h if k.get("cache_hit") or k.get("cache_disk")),
            disk_hits=sum(1 for k in h if k.get("cache_disk")),
            packet_gathers=any(re.search(r"@gather_[48]x", k.get("ir").getvalue()) for k in h
                               if k.get("ir") is not None))


def _once(dr, fn) -> float:
    """Seconds for fn() and the evaluation of what it returns."""
    t = time.perf_counter()
    dr.eval(*fn())
    dr.sync_thread()
    return time.perf_counter() - t


def _device_bytes(dr, holder, prefix: str) -> int:
    """Bytes of the Dr.Jit arrays among `holder`'s attributes whose names start with prefix
    (the BVH nodes' "records" of its WideNodes, a TriangleSet's per-triangle "t" arrays)."""
    total = 0
    for name, value in vars(holder).items():
        if name.startswith(prefix) and dr.is_array_v(value) and dr.width(value) > 1:
            total += dr.width(value) * max(dr.size_v(value), 1) * dr.itemsize_v(value)
    return total


class _MitsubaScene:
    """The same mesh and rays in Mitsuba llvm_ad_rgb (Embree). Mitsuba runs with FastMath on,
    its default; raycheck's kernels need it off, so each call switches it."""

    def __init__(self, dr, pos, faces, normals, o_np, d_np) -> None:
        from raycheck.mitsuba_ref import variant

        mi = variant.use("llvm_ad_rgb")
        self.dr, self.mi = dr, mi
        with self._fast_math():
            t0 = time.perf_counter()
            mesh = mi.Mesh("bumpy_sphere", len(pos), len(faces), has_vertex_normals=True)
            params = mi.traverse(mesh)
            params["vertex_positions"] = mi.Float(pos.ravel())
            params["faces"] = mi.UInt32(faces.astype(np.uint32).ravel())
            params["vertex_normals"] = mi.Float(normals.ravel())
            params.update()
            self.scene = mi.load_dict({"type": "scene", "mesh": mesh})
            dr.sync_thread()
            self.build_s = time.perf_counter() - t0
            self.ray = mi.Ray3f(mi.Point3f(o_np.T), mi.Vector3f(d_np.T))
            dr.eval(self.ray)

    @contextlib.contextmanager
    def _fast_math(self):
        dr = self.dr
        old = dr.flag(dr.JitFlag.FastMath)
        dr.set_flag(dr.JitFlag.FastMath, True)
        try:
            yield
        finally:
            dr.set_flag(dr.JitFlag.FastMath, old)

    def preliminary(self):
        with self._fast_math():
            pi = self.scene.ray_intersect_preliminary(self.ray)
            self.dr.eval(pi.t, pi.prim_index)
        return pi.t, pi.prim_index

    def full(self):
        with self._fast_math():
            si = self.scene.ray_intersect(self.ray)
            self.dr.eval(si)
        return (si,)

    def t(self) -> np.ndarray:
        return np.asarray(self.preliminary()[0].numpy())


# --- one mesh size ------------------------------------------------------------------------------
def measure(triangles: int, rays: int = RAYS, warm_runs: int = WARM_RUNS,
            brute_max: int = BRUTE_MAX_TRIANGLES, render: bool = True,
            mitsuba: bool = True, renderers: list | None = None) -> ThroughputRow:
    """All numbers for one mesh size. The warm closest-hit timings of ours and Mitsuba's are
    taken in interleaved rounds (best of warm_runs each), so that load from elsewhere on the
    machine hits both alike. The Renderer is appended to `renderers` when given (for
    interleaved render timings across sizes), else freed."""
    import raycheck.tracer.accel.intersect as ti
    from raycheck.tracer.kernel.backend import import_drjit
    from raycheck.tracer.kernel.vecmath import make_types

    dr = import_drjit()
    T = make_types()
    jit = _Jit(dr)
    res = int(round(math.sqrt(rays)))
    pos, faces, normals = bumpy_sphere(triangles)
    o_np, d_np = camera_rays(res)
    n = len(o_np)
    # the row's fields as they are measured (ThroughputRow's names)
    row: dict[str, Any] = dict(triangles=len(faces), vertices=len(pos), rays=n,
                               threads=dr.thread_count())

    # our BVH: build (timed inside the Intersector), upload
    flat = flat_scene(pos, faces, normals)
    built = []
    orig = ti.build_bvh

    def timed_build(v):
        t, cpu = time.perf_counter(), time.process_time()
        bvh = orig(v)
        built.append((time.perf_counter() - t, time.process_time() - cpu))
        return bvh

    ti.build_bvh = timed_build
    try:
        t0 = time.perf_counter()
        isect = ti.Intersector(flat, T, "bvh")
        dr.sync_thread()
        setup = time.perf_counter() - t0
    finally:
        ti.build_bvh = orig
    bvh = isect.triangles.bvh
    assert bvh is not None  # the "bvh" accelerator builds one
    if not built:  # the Intersector no longer calls tracer.accel.intersect.build_bvh: time it apart
        t, cpu = time.perf_counter(), time.process_time()
        orig(flat.triangles.vertices)
        built.append((time.perf_counter() - t, time.process_time() - cpu))
        setup += built[0][0]
    row.update(build_s=built[0][0], build_cpu_s=built[0][1], upload_s=setup - built[0][0],
               nodes=bvh.node_count,
               leaves=int(np.sum(bvh.count > 0)), depth=bvh.depth,
               node_bytes=_device_bytes(dr, isect.triangles.nodes, "records"),
               triangle_bytes=_device_bytes(dr, isect.triangles, "t"),
               order_bytes=int(bvh.order.nbytes))
    o, d = T.Array3f(o_np.T), T.Array3f(d_np.T)
    dr.eval(o, d)
    jit.take()

    ours = functools.partial(_closest, isect, o, d)
    ours_full = functools.partial(_closest, isect, o, d, normals=True)

    ours_cold_s, jit_cold = _once(dr, ours), jit.take()
    row.update(ours_cold_s=ours_cold_s, jit_cold=jit_cold,
               ours_full_cold_s=_once(dr, ours_full))
    h = isect.closest(o, d)
    dr.eval(h.t, h.order)
    t_ours, tri_ours = h.t.numpy(), h.order.numpy()
    row.update(hit_fraction=float(np.mean(t_ours < ti.FLT_MAX)))
    jit.take()
    contenders: dict[str, Callable[[], Any]] = {"ours": ours, "ours_full": ours_full}
    mis = None
    if mitsuba:
        mis = _MitsubaScene(dr, pos, faces, normals, o_np, d_np)
        row.update(mi_build_s=mis.build_s, mi_prelim_cold_s=_once(dr, mis.preliminary),
                   mi_full_cold_s=_once(dr, mis.full))
        contenders.update(mi_prelim=mis.preliminary, mi_full=mis.full)
    best = {k: math.inf for k in contenders}
    warm = JitCounts(kernels=0, cache_hits=0)
    for _ in range(max(1, warm_runs)):
        for name, fn in contenders.items():
            if name == "ours":
                jit.take()
            best[name] = min(best[name], _once(dr, fn))
            if name == "ours":
                j = jit.take()
                warm = JitCounts(kernels=warm.kernels + j.kernels,
                                 cache_hits=warm.cache_hits + j.cache_hits)
    mrays = {name: n / seconds / 1e6 for name, seconds in best.items()}
    row.update(jit_warm=warm, ours_warm_s=best["ours"], ours_mrays=mrays["ours"],
               ours_full_warm_s=best["ours_full"], ours_full_mrays=mrays["ours_full"])
    if mis is not None:
        t_mi = mis.t()
        ours_hit, mi_hit = t_ours < ti.FLT_MAX, np.isfinite(t_mi)
        with np.errstate(invalid="ignore"):
            close = np.abs(t_ours - t_mi) <= 1e-4 * np.abs(t_mi)
        row.update(mi_prelim_warm_s=best["mi_prelim"], mi_prelim_mrays=mrays["mi_prelim"],
                   mi_full_warm_s=best["mi_full"], mi_full_mrays=mrays["mi_full"],
                   vs_mitsuba_prelim=mrays["ours"] / mrays["mi_prelim"],
                   vs_mitsuba_full=mrays["ours_full"] / mrays["mi_full"],
                   mi_agree=float(np.mean((ours_hit == mi_hit)
                                          & (~(ours_hit & mi_hit) | close))))
        del mis
        jit.take()

    # brute force on an evenly strided subset of the rays
    if triangles <= brute_max:
        stride = max(1, int(math.ceil(len(o_np) * len(faces) / BRUTE_RAY_WORK)))
        ob, db = T.Array3f(o_np[::stride].T), T.Array3f(d_np[::stride].T)
        dr.eval(ob, db)
        brute = ti.Intersector(flat, T, "brute")

        def brute_hits():
            hb = brute.closest(ob, db)
            return hb.t, hb.order, hb.normal

        _once(dr, brute_hits)
        bw = min(_once(dr, brute_hits) for _ in range(2))
        hb = brute.closest(ob, db)
        dr.eval(hb.t, hb.order)
        row.update(brute_rays=dr.width(ob), brute_warm_s=bw, brute_mrays=dr.width(ob) / bw / 1e6,
                   brute_mtests=dr.width(ob) * len(faces) / bw / 1e6,
                   brute_agrees=bool(np.array_equal(hb.t.numpy(), t_ours[::stride])
                                     and np.array_equal(hb.order.numpy(), tri_ours[::stride])))
        del brute
        jit.take()
    del isect, ours, ours_full, contenders  # its BVH and arrays freed before the render below

    if render:
        from raycheck.tracer.options import RenderOptions
        from raycheck.tracer.render import Renderer

        t0 = time.perf_counter()
        r = Renderer(course_scene(pos, faces, normals), RenderOptions(width=res, height=res,
                                                                shadows=True))
        setup_s = time.perf_counter() - t0
        jit.take()
        t0 = time.perf_counter()
        r.render()
        dr.sync_thread()
        row.update(render_setup_s=setup_s, render_cold_s=time.perf_counter() - t0,
                   render_jit_cold=jit.take())
        times = []
        for _ in range(max(1, warm_runs)):
            t0 = time.perf_counter()
            r.render()
            dr.sync_thread()
            times.append(time.perf_counter() - t0)
        row.update(render_warm_s=min(times))
        if renderers is not None:
            renderers.append(r)
        del r
    row.update(peak_rss_mb=resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024)
    dr.set_flag(dr.JitFlag.KernelHistory, False)
    return ThroughputRow(**row)


# --- all sizes ----------------------------------------------------------------------------------
def run_throughput(sizes=SIZES, rays: int = RAYS, warm_runs: int = WARM_RUNS,
                   brute_max: int = BRUTE_MAX_TRIANGLES, render: bool = True,
                   mitsuba: bool = True, fresh_cache: bool = False) -> list[ThroughputRow]:
    """One row per mesh size (see measure). With fresh_cache, in a child process whose
    Dr.Jit kernel cache starts empty."""
    if fresh_cache:
        args = [list(sizes), rays, warm_runs, brute_max, render, mitsuba]
        with tempfile.TemporaryDirectory() as home:
            code = ("import json, sys; "
                    "from raycheck.harness.bench.throughput import run_throughput as r; "
                    "print(json.dumps([row.to_json() for row in r(*json.loads(sys.argv[1]))]))")
            proc = subprocess.run([sys.executable, "-c", code, json.dumps(args)],
                                  capture_output=True, text=True, check=True,
                                  env=dict(os.environ, HOME=home),
                                  cwd=Path(__file__).resolve().parent.parent)
        last = proc.stdout.strip().splitlines()[-1]
        return [ThroughputRow.from_json(r) for r in json.loads(last)]
    renderers: list = []
    rows = [measure(n, rays, warm_runs, brute_max, render, mitsuba, renderers) for n in sizes]
    if render and len(renderers) == len(rows) > 1:
        # the scaling curve from interleaved rounds over all sizes (load hits all alike)
        from raycheck.tracer.kernel.backend import import_drjit

        dr = import_drjit()
        for _ in range(max(1, warm_runs)):
            for i, r in enumerate(renderers):
                t0 = time.perf_counter()
                r.render()
                dr.sync_thread()
                seconds = time.perf_counter() - t0
                best = rows[i].render_warm_s
                if best is None or seconds < best:
                    rows[i] = dataclasses.replace(rows[i], render_warm_s=seconds)
    renderers.clear()
    return rows
