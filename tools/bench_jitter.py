"""The jitter test measured (prints tables, never pass/fail):

* cost: rendering K realisations of a case, cold (no cache) and from the cache;
* false alarms: the tracer itself as candidate (in process, seeds 0..N-1, the reference's are
  distribution.REFERENCE_SEED + i) on every jittered bundled case, share of seeds failing;
* power: the share of seeds detected for defects injected in process (tools/jitter_defects.py).

    .venv/bin/python tools/bench_jitter.py [--seeds 200] [--size 32] [--power-seeds 20]
"""
from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import jitter_defects as defects  # noqa: E402

from raycheck.harness.cases import case_matrix  # noqa: E402
from raycheck.harness.catalog import bundled, with_depth_range  # noqa: E402
from raycheck.harness.judge.statistics import JitterTest, prepare  # noqa: E402
from raycheck.harness.judge.verdict import jitter_result  # noqa: E402
from raycheck.harness.renderers import MitsubaRenderer, TracerRenderer  # noqa: E402
from raycheck.harness.storage.distribution import (  # noqa: E402
    DEFAULT_REALISATIONS,
    reference_distribution,
)
from raycheck.tracer.options import RenderOptions
from raycheck.tracer.render import Renderer  # noqa: E402
from raycheck.tracer.scene import load_scene  # noqa: E402
from raycheck.tracer.scene.request import request_fields  # noqa: E402

POWER_SCENES = ("course/spheres_mirror", "features/shadows")
POWER_SIZES = (64, 128)
# defect -> (feature of the case it is injected into, images of (scene, request))
DEFECTS = {
    "brightness x1.02": ("jitter", lambda s, r: defects.brightness(s, r, 1.02)),
    "brightness x1.05": ("jitter", lambda s, r: defects.brightness(s, r, 1.05)),
    "4 samples": ("jitter", lambda s, r: defects.samples(s, r, 4)),
    "64 samples": ("jitter", lambda s, r: defects.samples(s, r, 64)),
    "no jitter": ("jitter", defects.no_jitter),
    "one pattern for all pixels": ("jitter", defects.shared),
    "offsets in [0, 0.5)": ("jitter", defects.half),
    "filter applied twice": ("jitter+filter", defects.filter_twice),
}


def jittered_cases(size: int, names: tuple[str, ...] | None = None,
                   folders: tuple[str, ...] = ("course", "features")):
    for scene in map(with_depth_range, [s for f in folders for s in bundled(f)]):
        if names and f"{scene.path.parent.name}/{scene.name}" not in names:
            continue
        for case in case_matrix(scene, scene.size or (size, size))[0]:
            if case.jittered:
                yield case


def prepared(dist, kinds) -> dict:
    """kind -> the test's Reference of the distribution (the tracer's float candidates have
    the reference's channels: no replication)."""
    return {k: prepare(d.bytes, d.poisoned) for k, d in dist.kinds.items() if k in kinds}


def judged(images: dict, refs: dict) -> list[str]:
    """Names of the kinds that fail."""
    return [k for k, ref in refs.items() if not jitter_result(images[k], ref, None).passed]


def seeded_renders(case, seeds):
    """The tracer's images of the case for each seed, one renderer whose seed changes (only
    the stream seed, a runtime value, differs: one scene load and BVH build)."""
    r = Renderer(load_scene(case.scene.path), RenderOptions(**request_fields(case.request)))
    for seed in seeds:
        r.opts = replace(r.opts, seed=seed)
        result = r.render()
        yield {k: getattr(result, k) for k in case.request.kinds}


def cost(k: int) -> None:
    print(f"\nCost of {k} realisations (128x128, every kind of the case; seconds)")
    print(f"{'case':34} {'reference':9} {'cold':>7} {'cached':>7}")
    for case in jittered_cases(128, ("course/spheres_mirror", "course/smooth_mesh")):
        for ref in (TracerRenderer(), MitsubaRenderer()):
            cold = reference_distribution(ref, case.scene.path, case.request, k,
                                          use_shipped=False).seconds
            start = time.perf_counter()
            reference_distribution(ref, case.scene.path, case.request, k)
            print(f"{case.id:34} {ref.name:9} {cold:7.2f} {time.perf_counter() - start:7.3f}")


def false_alarms(size: int, n: int, k: int, folders: tuple[str, ...]) -> None:
    print(f"\nFalse alarms: the tracer as candidate, seeds 0..{n - 1}, against {k} "
          f"realisations, {size}x{size} (nominal {JitterTest().alpha:g} per image)")
    print(f"{'case':34} {'images':>6} {'failed':>6} {'rate':>8}")
    total = failed_total = 0
    for case in jittered_cases(size, folders=folders):
        refs = prepared(reference_distribution(TracerRenderer(), case.scene.path,
                                               case.request, k), case.request.kinds)
        failed = sum(len(judged(images, refs))
                     for images in seeded_renders(case, range(n)))
        images = n * len(case.request.kinds)
        total, failed_total = total + images, failed_total + failed
        print(f"{case.id:34} {images:6} {failed:6} {failed / images:8.4f}", flush=True)
    print(f"{'all':34} {total:6} {failed_total:6} {failed_total / total:8.4f}")


def power(n: int, k: int) -> None:
    print(f"\nPower: share of {n} seeds detected (color image; {', '.join(POWER_SCENES)}; "
          f"against {k} realisations)")
    cols = [f"{s} {z}" for s in POWER_SCENES for z in POWER_SIZES]
    print(f"{'defect':28} " + " ".join(f"{c.split('/')[1]:>20}" for c in cols))
    dists = {}
    for name, (feature, make) in DEFECTS.items():
        shares = []
        for scene in POWER_SCENES:
            for size in POWER_SIZES:
                case = next(c for c in jittered_cases(size, (scene,)) if c.feature == feature)
                key = (case.id, size)
                if key not in dists:
                    dists[key] = prepared(reference_distribution(
                        TracerRenderer(), case.scene.path, case.request, k), ("color",))
                hits = sum(bool(judged(make(case.scene.path, replace(case.request, seed=s)),
                                       dists[key])) for s in range(n))
                shares.append(hits / n)
        print(f"{name:28} " + " ".join(f"{v:20.2f}" for v in shares), flush=True)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--seeds", type=int, default=200, help="false-alarm seeds per case")
    ap.add_argument("--size", type=int, default=32, help="false-alarm image side")
    ap.add_argument("--power-seeds", type=int, default=20)
    ap.add_argument("--realisations", type=int, default=DEFAULT_REALISATIONS)
    ap.add_argument("--only", choices=("cost", "false-alarms", "power"))
    ap.add_argument("--folders", default="course,features",
                    help="bundled scene folders of the false-alarm table")
    args = ap.parse_args()
    # a cache of its own: the cold costs are cold, and the user's cache is left alone
    os.environ["RAYCHECK_CACHE"] = tempfile.mkdtemp(prefix="raycheck-bench-")
    start = time.perf_counter()
    if args.only in (None, "cost"):
        cost(args.realisations)
    if args.only in (None, "power"):
        power(args.power_seeds, args.realisations)
    if args.only in (None, "false-alarms"):
        false_alarms(args.size, args.seeds, args.realisations, tuple(args.folders.split(",")))
    print(f"\n{time.perf_counter() - start:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
