"""Course mode against the course program itself: every render of tests/data (the course's
own sample solution run on every bundled scene, comments stripped, at two sizes with four flag
sets; see tests/data/README.md) is reproduced byte for byte.

The data is regenerated with the course program's render_all.py whenever a bundled scene
changes: the manifest's sha256 prefixes must match the scene files."""
from __future__ import annotations

import hashlib
from pathlib import Path

import numpy as np
from course_renders import DATA, ENTRIES, KINDS, Entry

from raycheck.tracer.image import to_rgb8
from raycheck.tracer.options import RenderOptions
from raycheck.tracer.render import Renderer
from raycheck.tracer.scene import load_scene

REPO = Path(__file__).resolve().parents[2]


def test_the_data_covers_every_bundled_scene_as_it_is_now():
    """A changed or new scene needs the data regenerated (render_all.py)."""
    scenes = sorted(p.relative_to(REPO / "scenes").with_suffix("").as_posix()
                    for p in (REPO / "scenes").glob("*/*.txt"))
    assert sorted({e.scene for e in ENTRIES}) == scenes
    stale = sorted({e.scene for e in ENTRIES if e.sha256 != hashlib.sha256(
        (REPO / "scenes" / f"{e.scene}.txt").read_bytes()).hexdigest()[:len(e.sha256)]})
    assert stale == [], "scenes changed since the course program rendered them"
    assert len(ENTRIES) == 8 * len(scenes)


def _compare(got: np.ndarray, want: np.ndarray) -> tuple[int, int]:
    """(pixels more than one level off, pixels not byte-equal) of two uint8 HxWx3 images."""
    diff = np.abs(got.astype(np.int16) - want.astype(np.int16)).max(axis=2)
    return int((diff > 1).sum()), int((diff > 0).sum())


def test_course_mode_reproduces_every_course_program_render(full_run: bool):
    """The full run renders all of the data. The quick run renders every scene with its four
    flag sets at one of its two sizes, the sizes alternating from scene to scene, so both
    image shapes (33x47, 40x30) are still covered, in half the renders."""
    data = np.load(DATA)
    by_scene: dict[str, list[Entry]] = {}
    for e in ENTRIES:
        by_scene.setdefault(e.scene, []).append(e)
    if not full_run:
        for i, (scene_name, entries) in enumerate(by_scene.items()):
            sizes = sorted({(e.width, e.height) for e in entries})
            by_scene[scene_name] = [e for e in entries if (e.width, e.height) == sizes[i % 2]]
    rows = []
    total_pixels = total_unequal = 0
    for scene_name, entries in by_scene.items():
        scene = load_scene(REPO / "scenes" / f"{scene_name}.txt")
        shared = None  # one BVH and octree build per scene, for every size and flag set
        off, worst, pixels, unequal = 0, 1.0, 0, 0
        for e in entries:
            opts = RenderOptions(e.width, e.height, bounces=e.bounces, shadows=e.shadows,
                                 kinds=("color", "normals", "depth"), depth_min=e.depth[0],
                                 depth_max=e.depth[1])
            renderer = Renderer(scene, opts, shared)
            shared = renderer.isect
            r = renderer.render()
            bad = False
            for kind, image in zip(KINDS, (r.color, r.normals, r.depth)):
                far, ne = _compare(to_rgb8(image), data[e.key(kind)])
                n = e.width * e.height
                worst = min(worst, 1.0 - far / n)
                pixels, unequal, bad = pixels + n, unequal + ne, bad or far > 0
            off += bad
        rows.append((scene_name, off, len(entries), worst, 1.0 - unequal / pixels))
        total_pixels, total_unequal = total_pixels + pixels, total_unequal + unequal
    failing = [r for r in rows if r[1] or r[4] < 1.0]
    table = "\n".join(f"{s:36} {o:2}/{n} renders off  worst within one {w:8.4%}  "
                      f"byte-equal {b:8.4%}" for s, o, n, w, b in failing)
    assert not failing, (f"{len(failing)} scenes differ from the course program "
                         f"({total_unequal} of {total_pixels} pixels not byte-equal):\n{table}")
