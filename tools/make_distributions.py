"""Makes the shipped reference distributions (harness/storage/shipped.py): every jittered case of
`raycheck check` on the bundled scenes at their default sizes, K realisations of the reference
(the tracer in course mode), written to scenes/distributions/ with its index.json; files of
cases no longer in the matrix are removed. Run it when the tracer renders a jittered case of a
bundled scene differently (tests/harness/test_shipped.py says so) or a bundled scene changes.

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


def cases() -> tuple[list[Case], Renderer, int]:
    """The jittered cases of a check of the bundled scenes at their default sizes, with the
    reference that judges them."""
    from raycheck.harness.commands.check_config import CheckConfig

    # the candidate plays no part in the reference's distributions
    matrix = CheckConfig(renderer="tracer").matrix()
    jittered, _ = matrix.cases()
    return [c for c in jittered if c.jittered], matrix.reference, matrix.settings.realisations


def file_name(case: Case) -> str:
    from raycheck.harness.pipeline.matrix import slug

    return f"{slug(case.scene.id.replace('/', '-'))}-{slug(case.feature)}.npz"


def render(index: int) -> tuple[str, str, dict]:
    """The index-th case's key, file name and each kind's realisations and poisoned counts."""
    from raycheck.harness.storage import shipped
    from raycheck.harness.storage.distribution import REFERENCE_SEED, render_realisations

    found, reference, k = cases()
    case = found[index]
    kinds = render_realisations(reference, case.scene.path, case.request, k)
    key = shipped.shipped_key(reference, case.scene.path, case.request, k, REFERENCE_SEED)
    return key, file_name(case), {kind: (d.bytes, np.rint(d.poisoned * k).astype(np.int64))
                                  for kind, d in kinds.items()}


def main(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(prog="make_distributions.py", description=__doc__.split(
        "\n\n")[0])
    parser.add_argument("-j", type=int, default=2, help="processes (default 2)")
    args = parser.parse_args(argv)
    from raycheck.harness.storage import shipped

    found, _, _ = cases()
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
    total = sum(p.stat().st_size for p in shipped.FOLDER.glob("*.npz"))
    print(f"{len(found)} distributions, {total / 1e6:.1f} MB, in "
          f"{time.perf_counter() - start:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
