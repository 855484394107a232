"""Where a program crashes, by contrast across its cases: a program killed by a signal on every
case of some scenes that passes every case of others is wrong in a starter function that runs
in each scene it crashes on and in none it passes, where one alone does so. Most of what a
student fills in runs in every scene (Renderer::Render, traceRay, Material::shade); an
intersect runs only where the scene holds objects of its kind, Transform::intersect where
objects are transformed, a light's getIllumination where lights of its type shine. A null
material read in shade is the typical such crash: an intersect that reports a hit it did not
record, in the scenes that hold what it draws and show the background somewhere (a scene
whose every ray hits something fails without crashing, and says nothing here).

A case whose crash the debugger located (crash_site.py) or a flag explains (case.py's
crash_located) keeps its finding; a scene some of whose cases crash and some not says the
crash follows the flags, and the rule says nothing.
"""
from __future__ import annotations

from ..cases import Case
from ..records import CaseRecord, Verdict
from .cross_case import Swaps
from .localise import NO_IMAGE, TRANSFORM, Located, case_scene, intersects

# what a scene holds for each function to run, in words
HOLDS = {"Sphere::intersect": "spheres", "Plane::intersect": "planes",
         "Triangle::intersect": "triangles or meshes", TRANSFORM: "transformed objects",
         "PointLight::getIllumination": "point lights",
         "DirectionalLight::getIllumination": "directional lights"}


def crashed(row: CaseRecord) -> bool:
    return row.error is not None and row.error.code == "crash"


def crash_narrowings(cases: list[Case], rows: list[CaseRecord]) -> Swaps:
    """For each case (by index) of one program whose kinds lead with a bare crash, where the
    scenes it crashes on and those it passes single out one function: that crash finding -> a
    located one, then the crash."""
    by_scene: dict[str, list[bool]] = {}  # scene -> whether each case crashed
    by_passing: dict[str, list[bool]] = {}  # ... whether each passed
    first: dict[str, Case] = {}
    for case, row in zip(cases, rows):
        by_scene.setdefault(row.scene, []).append(crashed(row))
        by_passing.setdefault(row.scene, []).append(row.verdict == Verdict.PASS)
        first.setdefault(row.scene, case)
    hit = [s for s, c in by_scene.items() if all(c)]
    clean = [s for s, rows_of in by_passing.items() if all(rows_of)]
    if not hit or not clean or any(any(c) and not all(c) for c in by_scene.values()):
        return {}
    runs: dict[str, set[str]] = {}
    for name in hit + clean:
        scene = case_scene(first[name])
        if scene is None:
            return {}
        runs[name] = {*intersects(scene), *(f"{type(light).__name__}::getIllumination"
                                            for light in scene.lights)}
    left = set.intersection(*(runs[s] for s in hit)) - set[str]().union(*(runs[s] for s in clean))
    if len(left) != 1:
        return {}
    function = left.pop()
    out: Swaps = {}
    for i, row in enumerate(rows):
        bare = [k.findings[0] for k in row.kinds if k.findings and k.findings[0].code == "crash"]
        if not crashed(row) or not bare:
            continue
        assert row.error is not None  # crashed
        located = Located((function,), (
            f"it is {row.error.message} on every case of the {_scenes(hit, HOLDS[function])} "
            f"and passes every case of the {_scenes(clean, 'without')}: of the starter "
            f"functions, {function} alone runs in every scene it crashes on and in none it "
            "passes")
        ).finding(NO_IMAGE).record()
        out[i] = {finding: (located, finding) for finding in bare}
    return out


def _scenes(names: list[str], which: str) -> str:
    """'2 scenes holding spheres (a, b)', '1 scene without (c)'."""
    holding = which if which == "without" else f"holding {which}"
    return f"{len(names)} scene{'s' if len(names) > 1 else ''} {holding} " \
        f"({', '.join(sorted(names))})"
