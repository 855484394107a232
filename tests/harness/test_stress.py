"""raycheck stress on a few extreme scenes at tiny sizes: the table's numbers are consistent."""
from __future__ import annotations

import json

import numpy as np

from raycheck.harness.catalog import bundled
from raycheck.harness.commands.stress import nonfinite_pixels, run_stress, sort_key
from raycheck.harness.records import StressRow, from_json
from raycheck.harness.renderers import stress_variants


def test_stress_table_is_consistent(tmp_path):
    picked = [s for s in bundled("extreme")
              if s.name in ("falloff_zero_shadows", "offset_1e5", "size_1x9")]
    variants = {k: v for k, v in stress_variants().items() if k != "mitsuba"}
    rows = run_stress(picked, tmp_path / "report", variants, size=(12, 10))
    folder = tmp_path / "report"
    assert len(rows) == len(picked) * len(variants)
    assert rows == sorted(rows, key=sort_key)
    for r in rows:
        img = np.load(folder / r.floats)
        assert r.nonfinite == nonfinite_pixels(img)
        assert (folder / r.image).exists()
        if not r.passed:
            assert (folder / r.diff).exists()
    course_nan = [r for r in rows if r.scene == "falloff_zero_shadows"
                  and r.variant == "course"][0]
    assert course_nan.nonfinite > 0
    assert all(r.nonfinite == 0 for r in rows if r.variant == "robust")
    page = (folder / "stress.html").read_text()
    saved = json.loads((folder / "stress.json").read_text())
    assert [from_json(StressRow, r) for r in saved] == rows
    assert "<script" not in page.split("</table>")[0].split("<table>")[1]


def test_scene_text_is_escaped():
    from raycheck.harness.pages.stresspage import stress_page

    row = StressRow(scene="<b>x</b>", variant="robust", size=(2, 2), nonfinite=0,
                    differing=0.5, ssim=0.5, cold_s=0.1, warm_s=0.1, passed=False,
                    description='"<script>"', image="a.png", reference="r.png", diff="d.png",
                    diff_scale=0.5)
    page = stress_page([row], 0.99)
    assert "<b>x</b>" not in page and "&lt;b&gt;x&lt;/b&gt;" in page
    assert "<script>" not in page
