"""Makes the shipped reference distributions (harness/storage/shipped.py): every jittered case of
`raycheck check` on the bundled scenes at their default sizes, K realisations of its reference
(the tracer in course mode), and of `raycheck report`, K realisations of Mitsuba's, written to
scenes/distributions/ with its index.json and made_on.json (the CPU's vector instruction set,
on which Mitsuba's bytes depend); files of cases no longer in either matrix are
removed. Run it when the tracer or the Mitsuba side renders a jittered case of a bundled scene
differently (tests/harness/test_shipped.py says so) or a bundled scene changes.

    .venv/bin/python tools/make_distributions.py [-j N]
"""
from __future__ import annotations

import argparse
import json
import sys
import time
from concurrent.futures import ProcessPoolExecutor

import numpy as np

from raycheck.harness.cases import Case
from raycheck.harness.renderers import Renderer


def cases() -> list[tuple[Case, Renderer, int]]:
    """The jittered cases of a check and of the report of the bundled scenes, each with the
    reference that judges it and K."""
    from raycheck.harness.catalog import scenes_named
    from raycheck.harness.commands.check_config import CheckConfig
    from raycheck.harness.commands.report import ReportPlan
    from raycheck.harness.renderers import MitsubaRenderer, TracerRenderer

    # the candidate plays no part in the reference's distributions
    check = CheckConfig(renderer="tracer").matrix()
    report = ReportPlan(tuple(scenes_named([])), TracerRenderer(), MitsubaRenderer()).matrix()
    found = []
    for matrix in (check, report):
        jittered, _ = matrix.cases()
        found += [(c, matrix.reference, matrix.settings.realisations)
                  for c in jittered if c.jittered]
    return found


def file_name(case: Case, reference: Renderer) -> str:
    """course-arch-jitter.npz for the tracer's, mitsuba-course-arch-jitter.npz for Mitsuba's."""
    from raycheck.harness.pipeline.matrix import slug

    prefix = "" if reference.name == "tracer" else f"{slug(reference.name)}-"
    return f"{prefix}{slug(case.scene.id.replace('/', '-'))}-{slug(case.feature)}.npz"


def render(index: int) -> tuple[str, str, dict]:
    """The index-th case's key, file name and each kind's realisations and poisoned counts."""
    from raycheck.harness.storage import shipped
    from raycheck.harness.storage.distribution import REFERENCE_SEED, render_realisations

    case, reference, k = cases()[index]
    kinds = render_realisations(reference, case.scene.path, case.request, k)
    key = shipped.shipped_key(reference, case.scene.path, case.request, k, REFERENCE_SEED)
    return key, file_name(case, reference), {
        kind: (d.bytes, np.rint(d.poisoned * k).astype(np.int64)) for kind, d in kinds.items()}


def main(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(prog="make_distributions.py", description=__doc__.split(
        "\n\n")[0])
    parser.add_argument("-j", type=int, default=2, help="processes (default 2)")
    args = parser.parse_args(argv)
    from raycheck.harness.provenance import vector_isa
    from raycheck.harness.storage import shipped

    found = cases()
    start = time.perf_counter()
    index: dict[str, str] = {}
    with ProcessPoolExecutor(args.j) as pool:
        for key, name, kinds in pool.map(render, range(len(found))):
            index[key] = name
            shipped.write(shipped.FOLDER / name, kinds, key)
            print(f"{name}: {(shipped.FOLDER / name).stat().st_size / 1e3:.0f} kB", flush=True)
    for stale in shipped.FOLDER.glob("*.npz"):
        if stale.name not in index.values():
            stale.unlink()
    (shipped.FOLDER / shipped.INDEX).write_text(json.dumps(index, indent=1, sort_keys=True)
                                                + "\n", encoding="utf-8")
    (shipped.FOLDER / shipped.MADE_ON).write_text(json.dumps({"vector isa": vector_isa()})
                                                  + "\n", encoding="utf-8")
    total = sum(p.stat().st_size for p in shipped.FOLDER.glob("*.npz"))
    print(f"{len(found)} distributions, {total / 1e6:.1f} MB, in "
          f"{time.perf_counter() - start:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
