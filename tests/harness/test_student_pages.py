"""The pages a student and a teacher read, in Chromium at 1280 px (tests/cdp.py): a check of a
program with two mistakes opens with the diagnosis (overview, terminal, check.json), its case
page with the cause said once and a fixed row of labelled images; a program with a bug no
mistake of the catalogue makes gets it listed with where to look; a class's page says which
submission makes which mistake. Screenshots of the three pages are kept in out/screenshots/."""
from __future__ import annotations

import base64
import csv
import io
import json
import sys
from contextlib import redirect_stderr, redirect_stdout
from pathlib import Path

import pytest

from raycheck.harness.cli.check import main as check_main
from raycheck.harness.cli.grade import main as grade_main

REPO = Path(__file__).resolve().parents[2]
SPHERES = REPO / "scenes" / "course" / "spheres_mirror.txt"  # spheres, a plane; bounces 4
SHADOWS = REPO / "scenes" / "features" / "shadows.txt"  # no mirror: no bounces case
TRACER = f"{sys.executable} -m raycheck.tracer"
MISTAKES = "falloff_power=1,specular_half_vector"
SCREENSHOTS = REPO / "out" / "screenshots"
WIDTH = 1280
FEATURES = "plain,shadows,bounces,shadows+bounces"


def talking_program(folder: Path, command: str) -> str:
    """A program that writes a line of its own before it renders with `command`."""
    path = folder / "a2"
    path.write_text(f'#!/bin/sh\necho "a2: rendering $2"\nexec {command} "$@"\n')
    path.chmod(0o755)
    return str(path)


def run_check(out: Path, renderer: str, scenes: list[Path], features: str) -> tuple[int, str]:
    stdout = io.StringIO()
    with redirect_stdout(stdout), redirect_stderr(io.StringIO()):
        code = check_main(["--renderer", renderer, "--out", str(out), "--size", "24", "24",
                           "--features", features, "-j", "2", *map(str, scenes)])
    return code, stdout.getvalue()


@pytest.fixture(scope="module")
def student(tmp_path_factory):
    """A program with two mistakes (a light's falloff, Blinn's highlight) checked on two
    scenes: (the folder, check.json, what the terminal printed)."""
    tmp = tmp_path_factory.mktemp("student")
    program = talking_program(tmp, f"{TRACER} --mistake {MISTAKES}")
    code, printed = run_check(tmp / "check", program, [SPHERES, SHADOWS], FEATURES)
    assert code == 1
    return tmp / "check", json.loads((tmp / "check" / "check.json").read_text()), printed


def shot(browser, url: str, name: str) -> None:
    """Loads the page at WIDTH px and keeps its screenshot; no console errors, nothing wider
    than the window."""
    browser.call("Emulation.setDeviceMetricsOverride", width=WIDTH, height=900,
                 deviceScaleFactor=1, mobile=False)
    try:
        browser.load(url)
        assert browser.console_errors == []
        assert browser.evaluate("document.documentElement.scrollWidth") <= WIDTH
        SCREENSHOTS.mkdir(parents=True, exist_ok=True)
        data = browser.call("Page.captureScreenshot", format="png",
                            captureBeyondViewport=True)["data"]
        (SCREENSHOTS / f"{name}.png").write_bytes(base64.b64decode(data))
    finally:
        browser.call("Emulation.clearDeviceMetricsOverride")


def failing_cases(data: dict) -> set[str]:
    return {f"{c['scene']}/{c['feature']}" for c in data["cases"] if c["verdict"] != "pass"}


def test_check_json_says_which_mistakes_explain_which_cases(student):
    """Both mistakes found, the falloff first (it shows in every failing case, the highlight
    only where a light has one), every failing case explained, none left open."""
    _, data, _ = student
    d = data["diagnosis"]
    failing = failing_cases(data)
    assert d["failing_cases"] == len(failing) > 0
    assert [(m["mistake"], m["function"]) for m in d["mistakes"]] == [
        ("falloff_power=1", "PointLight::getIllumination"),
        ("specular_half_vector", "Material::shade")]
    assert set(d["mistakes"][0]["cases"]) == failing
    assert set(d["mistakes"][1]["cases"]) <= failing
    assert d["unexplained"] == []
    for m in d["mistakes"]:
        assert m["example"] in m["cases"] and m["page"].endswith("/index.html")
        assert m["command"].startswith("raycheck render -input ")
        assert m["mistake"] in m["command"].split(" --mistake ")[1].split(",")


def test_the_terminal_opens_with_the_diagnosis_grouped_by_cause(student):
    _, data, printed = student
    lines = [line for line in printed.splitlines() if not line.startswith("[")]  # progress
    n = len({(c["scene"], c["feature"]) for c in data["cases"]})
    assert lines[0] == (f"2 mistakes found in the {len(failing_cases(data))} failing cases "
                        f"(of {n}).")
    assert lines[1].startswith("  1. PointLight::getIllumination: your program divides a "
                               "point light's color by falloff * d^1")
    assert lines[4].startswith("  2. Material::shade: your program raises N.H")
    # the case table follows; a case's row names its cause briefly, not the whole message
    assert lines.index(f"{'scene':<34} {'feature':<20} {'verdict':<7} worst") == 8
    assert "explained by falloff_power + specular_half_vector (above)" in printed


def test_the_overview_reads_diagnosis_then_matrix_then_rows(student, browser):
    folder, data, _ = student
    shot(browser, (folder / "index.html").as_uri(), "overview")
    order = browser.evaluate("[...document.querySelectorAll('h1, #diagnosis, #summary, "
                             "#overview, #cases')].map(e => e.id || e.tagName)")
    assert order == ["H1", "diagnosis", "summary", "overview", "cases"]
    n = len({(c["scene"], c["feature"]) for c in data["cases"]})
    assert browser.evaluate("document.querySelector('#diagnosis h2').textContent") == \
        f"2 mistakes found in the {len(failing_cases(data))} failing cases (of {n})."
    items = browser.evaluate("[...document.querySelectorAll('#diagnosis ol.mistakes li')]"
                             ".map(li => li.textContent)")
    assert len(items) == 2 and items[0].startswith("PointLight::getIllumination: ")
    assert browser.evaluate("[...document.querySelectorAll('#overview thead th')]"
                            ".map(th => th.textContent)") == \
        ["scene", "plain", "shadows", "bounces", "shadows+bounces"]
    # the bounce count in the cell; the reason a scene has no case of a family on hover
    cells = browser.evaluate(
        "Object.fromEntries([...document.querySelectorAll('#overview tbody tr')].map(r => "
        "[r.cells[0].textContent, [...r.cells].slice(1).map(c => [c.textContent, c.title])]))")
    assert cells["course/spheres_mirror"][2][0] == "fail4 bounces"
    reason = next(s["reason"] for s in data["skipped"]
                  if s["scene"] == "features/shadows" and s["feature"] == "bounces4")
    assert cells["features/shadows"][2] == ["–", reason]


def test_the_case_page_opens_with_the_cause_once(student, browser):
    folder, _, _ = student
    shot(browser, (folder / "cases/course_spheres_mirror/plain/index.html").as_uri(), "case")
    title = "course/spheres_mirror · plain: fail"
    assert browser.evaluate("document.title") == title
    assert browser.evaluate("document.querySelector('h1').textContent") == title
    # the explanation first (after the scene's description), the combined cause said once
    assert browser.evaluate("document.querySelector('h1 ~ section').className") == \
        "explanation"
    assert browser.evaluate("document.querySelector('.explanation h2').textContent") \
        .startswith("Why: 2 mistakes together: the reference with them reproduces your "
                    "images: 100.0% of pixels match")
    assert browser.evaluate("[...document.querySelectorAll('.explanation li')]"
                            ".map(li => li.textContent.split(': ')[0])") == \
        ["PointLight::getIllumination", "Material::shade"]
    assert browser.evaluate("document.body.innerText.split('With this mistake').length") == 1
    # per kind, one row: yours, the reference, the reference with the mistakes, the difference
    labels = browser.evaluate("[...document.querySelectorAll('section.kind')].map(s => "
                              "[...s.querySelectorAll('.panels.row .panel > b')]"
                              ".map(b => b.textContent))")
    assert labels[0] == ["your program (a2)", "the reference (course program)",
                         "the reference with your mistakes",
                         "where they differ: |yours - the reference|, max over channels"]
    tops = browser.evaluate("[...document.querySelectorAll('.panels.row')].map(r => "
                            "[...r.querySelectorAll('.view')].map(v => "
                            "Math.round(v.getBoundingClientRect().top)))")
    assert all(len(set(t)) == 1 for t in tops)  # the images side by side, aligned
    assert browser.evaluate("document.querySelectorAll('section.kind table.numbers').length") \
        == 3
    # the program's own output last, folded
    assert browser.evaluate("document.querySelector('details#output').open") is False
    assert browser.evaluate("document.querySelector('details#output pre').textContent") \
        .startswith("a2: rendering")
    assert browser.evaluate("!!(document.querySelector('section.kind:last-of-type')"
                            ".compareDocumentPosition(document.querySelector('details#output'))"
                            " & Node.DOCUMENT_POSITION_FOLLOWING)")


def test_what_no_mistake_explains_is_listed_with_where_to_look(tmp_path):
    """Every sphere intersected at 0.8 times its radius (tests/wrappers/geometry_bugs.py): no
    mistake found; the case is listed with its located finding, Sphere::intersect."""
    renderer = f"{sys.executable} {REPO / 'tests' / 'wrappers' / 'corrupt.py'} sphere_shrunk"
    code, printed = run_check(tmp_path / "check", renderer, [SHADOWS], "plain")
    data = json.loads((tmp_path / "check" / "check.json").read_text())
    assert code == 1
    d = data["diagnosis"]
    assert d["mistakes"] == [] and d["failing_cases"] == 1
    (case,) = d["unexplained"]
    assert (case["case"], case["kind"], case["finding"]["code"]) == \
        ("features/shadows/plain", "color", "located")
    assert case["finding"]["message"].startswith("Sphere::intersect: no known mistake")
    assert [line for line in printed.splitlines() if not line.startswith("[")][:3] == [
        "No known mistake found in the 1 failing case (of 1); 1 of them unexplained.",
        "Failing cases no known mistake explains (1):",
        f"  features/shadows/plain (color): located: {case['finding']['message']}"]
    page = (tmp_path / "check" / "index.html").read_text()
    assert '<ul class="unexplained"><li><a href="cases/features_shadows/plain/' \
        'index.html">features/shadows/plain</a> (color): <b>located</b>: ' \
        'Sphere::intersect: no known mistake' in page


@pytest.fixture(scope="module")
def graded(tmp_path_factory):
    """A class of three: alice with the falloff mistake, bob with it and Blinn's highlight,
    carol with neither."""
    out = tmp_path_factory.mktemp("class") / "class"
    with redirect_stdout(io.StringIO()), redirect_stderr(io.StringIO()):
        code = grade_main([f"alice={TRACER} --mistake falloff_power=1",
                           f"bob={TRACER} --mistake {MISTAKES}", f"carol={TRACER}",
                           "--scenes", str(SPHERES), "--features", "plain", "--size", "24",
                           "24", "--out", str(out), "-j", "2", "--quiet", "--sandbox", "off"])
    assert code == 0
    return out


def test_the_class_says_who_makes_which_mistake(graded, browser):
    grades = json.loads((graded / "grades.json").read_text())
    assert [(m["mistake"], m["function"], m["submissions"]) for m in grades["mistakes"]] == [
        ("falloff_power", "PointLight::getIllumination", ["alice", "bob"]),
        ("specular_half_vector", "Material::shade", ["bob"])]
    assert {g["name"]: g["mistakes"] for g in grades["submissions"]} == {
        "alice": ["falloff_power=1"], "bob": ["falloff_power=1", "specular_half_vector"],
        "carol": []}
    rows = {r["name"]: r["mistakes"]
            for r in csv.DictReader(io.StringIO((graded / "grades.csv").read_text()))}
    assert rows == {"alice": "falloff_power=1",
                    "bob": "falloff_power=1 specular_half_vector", "carol": ""}
    shot(browser, (graded / "index.html").as_uri(), "class")
    table = ("[...document.querySelectorAll('#mistakes tbody tr')].map(r => "
             "[r.cells[0].textContent, r.cells[3].textContent, "
             "[...r.cells[4].querySelectorAll('a')].map(a => a.getAttribute('href'))])")
    assert browser.evaluate(table) == [
        ["falloff_power", "2", ["alice/index.html", "bob/index.html"]],
        ["specular_half_vector", "1", ["bob/index.html"]]]
    browser.evaluate("document.querySelectorAll('#mistakes th')[3].click()")  # fewest first
    assert [r[0] for r in browser.evaluate(table)] == ["specular_half_vector", "falloff_power"]
