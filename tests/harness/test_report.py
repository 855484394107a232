"""The HTML report: its JSON holds the metrics, every referenced file exists, scene text is
escaped, and a real headless Chromium loads the pages without errors and flips images."""
from __future__ import annotations

import json
import re
from dataclasses import replace
from pathlib import Path

import pytest

from raycheck.harness.bench.convergence import sweep
from raycheck.harness.case_settings import CaseSettings
from raycheck.harness.cases import case_matrix
from raycheck.harness.catalog import read_header
from raycheck.harness.commands.report import ReportPlan, build_report
from raycheck.harness.judge import metrics
from raycheck.harness.judge.verdict import ENGINES_TOLERANCE, comparable
from raycheck.harness.pipeline.case import run_case
from raycheck.harness.renderers import MitsubaRenderer, TracerRenderer

REPO = Path(__file__).resolve().parents[2]
HOSTILE = "<script>alert('x')</script> & \"quotes\""


@pytest.fixture(scope="module")
def report(tmp_path_factory) -> Path:
    tmp = tmp_path_factory.mktemp("report")
    scene = tmp / "hostile.txt"
    scene.write_text(f"# {HOSTILE}\n# flags: -depth 8 11\n# size: 12 10\n"
                     + (REPO / "scenes/features/odd_size.txt").read_text()
                     .replace("../assets", str(REPO / "scenes/assets")))
    scenes = [read_header(scene), read_header(REPO / "scenes/features/nonsquare.txt")]
    plan = ReportPlan(tuple(scenes), TracerRenderer(), MitsubaRenderer(), size=16,
                      sweep_scenes=())
    build_report(plan, tmp / "out", log=lambda s: None, quiet=True)
    return tmp / "out"


def test_json_holds_the_metrics_of_each_case(report: Path):
    data = json.loads((report / "report.json").read_text())
    row = next(c for c in data["cases"] if c["case"] == "nonsquare/plain")
    case = next(c for c in case_matrix(read_header(REPO / "scenes/features/nonsquare.txt"),
                                       tuple(row["size"]))[0] if c.feature == "plain")
    # deterministic: the same numbers again
    again = run_case(case, TracerRenderer(), MitsubaRenderer(), CaseSettings(ENGINES_TOLERANCE))
    for k in row["kinds"]:
        ref, got_img = comparable(again.images["reference"][k["kind"]],
                                  again.images["candidate"][k["kind"]])
        expected = dict(metrics.compare(ref, got_img).items())
        got = {n: float(v) for n, v in k["metrics"].items() if n in expected}
        assert got == pytest.approx(expected, rel=1e-9, abs=1e-12)
    assert data["provenance"]["mitsuba"] == "3.9.1" and data["provenance"]["drjit"] == "1.5.0"
    assert {s["reason"] for s in data["skipped"]} >= {
        "-bounces has no effect: no reflective material (|ks| > 0.1)"}


def test_every_referenced_file_exists(report: Path):
    pages = [report / "index.html"] + sorted(report.glob("cases/*/*/index.html"))
    assert len(pages) > 5
    for page in pages:
        text = page.read_text()
        refs = re.findall(r'(?:src|href|data-candidate|data-reference)="([^"#]+)"', text)
        assert refs, page
        for ref in refs:
            assert (page.parent / ref).exists(), f"{page}: {ref} is missing"


def test_scene_text_is_escaped(report: Path):
    page = next(report.glob("cases/*_hostile/plain/index.html")).read_text()
    assert "<script>alert" not in page
    assert "&lt;script&gt;alert(&#x27;x&#x27;)&lt;/script&gt; &amp; &quot;quotes&quot;" in page
    index = (report / "index.html").read_text()
    assert "<script>alert" not in index


def test_sweep_points_fall_with_more_samples():
    scene = read_header(REPO / "scenes/features/jitter_filter.txt")
    points = sweep(scene, [TracerRenderer(), MitsubaRenderer()], MitsubaRenderer(),
                   sample_counts=(1, 16), sizes=(24,), reference_samples=64,
                   sweep_size=24, size_sweep_samples=16)
    for renderer in ("tracer", "mitsuba"):
        one, many = (next(p for p in points if p.renderer == renderer and p.samples == n)
                     for n in (1, 16))
        assert many.rmse < one.rmse  # more samples, less error against the converged image
        assert one.warm_s > 0 and many.cold_s > 0


def test_index_and_case_pages_in_chromium(report: Path, browser):
    browser.load((report / "index.html").as_uri())
    assert browser.console_errors == []
    rows = browser.evaluate("document.querySelectorAll('#cases tbody tr').length")
    # filtering by status keeps only skipped rows
    browser.evaluate("const s=document.querySelector('select[data-col=status]');"
                     "s.value='skip'; s.dispatchEvent(new Event('input'))")
    shown = browser.evaluate("[...document.querySelectorAll('#cases tbody tr')]"
                             ".filter(r=>r.style.display!=='none').length")
    assert 0 < shown < rows
    # sorting by SSIM puts the rows in numeric order
    browser.evaluate("document.querySelectorAll('#cases th')[4].click()")
    ssim = browser.evaluate("[...document.querySelectorAll('#cases tbody tr')]"
                            ".map(r=>parseFloat(r.cells[4].dataset.v)).filter(v=>!isNaN(v))")
    assert ssim == sorted(ssim)

    browser.load((report / "cases/features_nonsquare/plain/index.html").as_uri())
    assert browser.console_errors == []
    before = browser.evaluate("document.querySelector('img.flip').src")
    browser.evaluate("document.querySelector('button.flipbtn').click()")
    after = browser.evaluate("document.querySelector('img.flip').src")
    assert before.endswith("color_candidate.png") and after.endswith("color_reference.png")
    assert browser.evaluate("document.querySelector('.flipname').textContent") == \
        "the reference (Mitsuba 3)"
    browser.evaluate("document.dispatchEvent(new KeyboardEvent('keydown', {key: 'f'}))")
    assert browser.evaluate("document.querySelector('img.flip').src") == before
    # every image decoded, and zoom scales them with nearest-neighbour pixels
    assert browser.evaluate("[...document.images].every(i => i.complete && i.naturalWidth > 0)")
    width = browser.evaluate("document.querySelector('img.flip').getBoundingClientRect().width")
    browser.evaluate("const z=document.getElementById('zoom'); z.value=2*z.value;"
                     "z.dispatchEvent(new Event('input'))")
    assert browser.evaluate(
        "document.querySelector('img.flip').getBoundingClientRect().width") == 2 * width
    assert browser.evaluate("getComputedStyle(document.images[0]).imageRendering") == "pixelated"


def test_thumbnail_sizes():
    from raycheck.harness.pages.imaging import THUMB_PX, thumb_shape

    assert THUMB_PX == 88  # twice the overview's 44 CSS pixels
    assert thumb_shape((128, 128, 3)) == (88, 88)
    assert thumb_shape((100, 40)) == (88, 35)  # 40 * 88 // 100
    assert thumb_shape((40, 800, 3)) == (4, 88)
    assert thumb_shape((88, 10)) is None and thumb_shape((12, 12, 3)) is None


def test_a_diff_thumbnail_keeps_a_single_differing_pixel_and_an_image_thumbnail_averages(
        tmp_path: Path):
    """Shrunk by the browser (nearest neighbour, as the page draws its images), one differing
    pixel of 128x128 would show in a 44-pixel thumbnail with a chance of about 1 in 8; the
    diff thumbnail takes each block's largest difference on the full heatmap's scale."""
    import numpy as np
    from PIL import Image

    from raycheck.harness.pages.imaging import (
        colormap,
        difference,
        save_diff_thumbnail,
        save_thumbnail,
    )

    ref = np.zeros((128, 128, 3), np.float32)
    got = ref.copy()
    got[77, 5] = (0.2, 1.0, 0.0)
    d, scale = difference(ref, got)
    assert scale == 1.0
    save_diff_thumbnail(tmp_path / "d.png", d, scale, (88, 88))
    thumb = np.asarray(Image.open(tmp_path / "d.png"))
    assert thumb.shape == (88, 88, 3)
    bright = np.all(thumb == colormap(np.array(1.0)), axis=2)
    assert bright.sum() == 1
    assert np.all(thumb[~bright] == colormap(np.array(0.0)))
    # a one-pixel checkerboard of 0 and 1 halved: every 2x2 block averages 0.5, byte 128
    board = (np.indices((176, 176)).sum(axis=0) % 2).astype(np.float32)
    save_thumbnail(tmp_path / "t.png", board, (88, 88))
    assert np.all(np.asarray(Image.open(tmp_path / "t.png")) == 128)


def test_the_overview_shows_thumbnails_of_the_color_image(tmp_path: Path):
    """A case larger than a thumbnail gets thumb_candidate.png and thumb_diff.png of its color
    image (of the first kind it has without one), which the overview cell shows; a smaller
    case shows its images."""
    from PIL import Image

    from raycheck.harness.pages.case_files import write_case_images
    from raycheck.harness.pipeline.matrix import case_record, overview_cells

    scene = read_header(REPO / "scenes/features/nonsquare.txt")
    for size, kinds, thumbs in [((100, 90), ("color", "normals"), (88, 79)),
                                ((100, 90), ("depth",), (88, 79)), ((40, 30), ("color",), None)]:
        case = next(c for c in case_matrix(scene, size)[0] if c.feature == "plain")
        case = replace(case, request=replace(case.request, kinds=kinds))
        result = run_case(case, TracerRenderer(), TracerRenderer(),
                          CaseSettings(ENGINES_TOLERANCE))
        folder = tmp_path / f"{size[0]}-{kinds[0]}"
        files = write_case_images(result, folder)
        shown = kinds[0]
        record = replace(case_record(result), page=f"{folder.name}/index.html", files=files,
                         kinds=(), scene="s")
        cell = overview_cells([record])[("s", "plain")]
        if thumbs is None:
            assert cell.thumbs == ((f"{folder.name}/{shown}_candidate.png", "candidate"),
                                   (f"{folder.name}/{shown}_diff.png", "diff"))
            assert not (folder / "thumb_candidate.png").exists()
            continue
        assert cell.thumbs == ((f"{folder.name}/thumb_candidate.png", "candidate"),
                               (f"{folder.name}/thumb_diff.png", "diff"))
        assert [k for k, names in files.items() if "thumb_candidate" in names] == [shown]
        for name in ("thumb_candidate.png", "thumb_diff.png"):
            assert Image.open(folder / name).size == thumbs


def test_the_index_is_there_when_the_comparisons_are_done(tmp_path: Path, monkeypatch, capsys):
    """The comparisons are swapped in whole before the sweeps run (they would keep a new user
    from the index as long again), then the index again with the sweeps' section; pages the
    report was not given say which command makes them."""
    from raycheck.harness.cli.report import main
    from raycheck.harness.commands import report as report_module

    out = tmp_path / "out"
    index = out / "report" / "index.html"
    seen = []

    def sweeps(plan, log):
        seen.append(index.read_text(encoding="utf-8"))
        return []

    monkeypatch.setattr(report_module, "run_sweeps", sweeps)
    scene = REPO / "scenes/course/spheres_mirror.txt"  # one of the swept scenes
    assert main([str(scene), "--out", str(out), "--size", "8", "--no-bench"]) == 0
    printed = capsys.readouterr().out
    assert len(seen) == 1 and "spheres_mirror" in seen[0]  # the cases' rows, before the sweeps
    assert "(the comparisons); the error-against-time sweeps follow" in printed
    assert re.search(r"^phases: other pages \d+\.\d s, comparisons \d+\.\d s, sweeps \d+\.\d s$",
                     printed, re.M)
    final = index.read_text(encoding="utf-8")
    for what, how in (("The extreme scenes in every mode", "raycheck stress"),
                      ("Render times and BVH throughput", "make bench"),
                      ("Which bug the top finding names", "make findings")):
        assert f"{what}: not in this report (<code>{how}</code> makes it)." in final
    assert [p.name for p in tmp_path.iterdir()] == ["out"] and \
        not [p for p in out.iterdir() if ".new-" in p.name]
