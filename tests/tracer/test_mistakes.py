"""The mistake catalogue (tracer/mistakes.py) and its switches in the kernel
(tracer/arithmetic/mistaken.py): spellings checked, one kernel for every switch setting, the
course's images exactly where every mistake is compiled in and none is on, and each mistake's
effect where it has one by hand."""
from __future__ import annotations

import ast
import importlib
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from raycheck.tracer.mistakes import (
    CATALOGUE,
    HOOKED,
    MISTAKES,
    Code,
    MistakeError,
    Needs,
    Switch,
    applicable,
    hooks,
    parse_switch,
    present,
    switches,
)
from raycheck.tracer.operators import GENERATED, GENERATED_CODES, Site
from raycheck.tracer.options import OptionError, RenderOptions
from raycheck.tracer.render import render
from raycheck.tracer.scene import load_scene
from raycheck.tracer.scene.request import RenderRequest

REPO = Path(__file__).resolve().parents[2]
SHADOWS = REPO / "scenes" / "features" / "shadows.txt"
BOUNCES = REPO / "scenes" / "features" / "bounces.txt"
KINDS = ("color", "normals", "depth")
ENTRY_OF = {m.code: Site(m.code.partition(".")[0]) for m in GENERATED}


def test_spellings_parse_and_are_checked_against_the_catalogue():
    assert parse_switch("falloff_power=1") == Switch("falloff_power", 1.0)
    assert parse_switch("shadow_missing") == Switch("shadow_missing")
    assert str(Switch("shadow_offset", 0.05)) == "shadow_offset=0.05"
    for text, message in [
        ("nope", "unknown mistake 'nope'"),
        ("shadow_offset", "mistake shadow_offset needs its offset: shadow_offset=VALUE"),
        ("shadow_missing=1", "mistake shadow_missing has no parameter"),
        ("shadow_offset=x", "mistake shadow_offset: 'x' is not a number"),
        ("shadow_offset=2", "mistake shadow_offset: its offset must be in [0, 1]"),
        ("reflection_depth=0.5", "mistake reflection_depth: its extra bounces must be a whole "
                                 "number"),
    ]:
        with pytest.raises(MistakeError) as e:
            parse_switch(text)
        assert str(e.value).startswith(message)
    with pytest.raises(MistakeError, match="mistake shadow_missing given twice"):
        switches(["shadow_missing", "shadow_missing"])
    # one canonical order: equal sets of switches are equal options
    assert switches(["shadow_missing", "falloff_power=3"]) == \
        (Switch("falloff_power", 3.0), Switch("shadow_missing"))


# the modules that compute mistakes: the course parts' subclasses, the kernel's camera rays and
# samples, the request rewrites
HOOK_MODULES = ("raycheck.tracer.arithmetic.mistaken", "raycheck.tracer.render",
                "raycheck.tracer.options")
# the course parts that compute the generated mistakes' sites (operators.py)
SITE_MODULES = ("raycheck.tracer.render", "raycheck.tracer.accel.intersect",
                "raycheck.tracer.accel.transform_sites",
                "raycheck.tracer.accel.triangles", "raycheck.tracer.shade.shading")


def test_every_catalogue_entry_has_one_hook_and_every_hook_an_entry():
    """The codes are the catalogue's, once each, and the generated ones; every one is declared
    by exactly one hook module (hooks() refuses a second), and each module's code names only
    the codes it declares, and each of them (read from its syntax tree: a misspelt member
    fails here)."""
    assert [m.code for m in CATALOGUE] == list(Code)
    modules = {name: importlib.import_module(name) for name in HOOK_MODULES + SITE_MODULES}
    assert HOOKED == {code: name for name, module in modules.items() for code in module.HOOKS}
    assert set(HOOKED) == set(Code) | GENERATED_CODES
    for name, module in modules.items():
        tree = ast.parse(Path(module.__file__).read_text())
        named = [node.attr for node in ast.walk(tree) if isinstance(node, ast.Attribute)
                 and isinstance(node.value, ast.Name) and node.value.id == "Code"]
        declared = {code.name for code in module.HOOKS if isinstance(code, Code)}
        assert set(named) <= set(Code.__members__), name
        assert set(named) == declared, name
        # each declared once in HOOKS and used at least once besides
        assert all(named.count(code) >= 2 for code in declared), name
        # a generated mistake's site is named where the module computes it, as Site.MEMBER
        sites = {node.attr for node in ast.walk(tree) if isinstance(node, ast.Attribute)
                 and isinstance(node.value, ast.Name) and node.value.id == "Site"}
        assert sites <= set(Site.__members__), name
        assert {Site[s] for s in sites} == {ENTRY_OF[code] for code in module.HOOKS
                                            if code in GENERATED_CODES}, name


def test_a_hook_takes_codes_only_and_a_code_has_one_module():
    from raycheck.tracer.arithmetic.mistaken import Switches

    on = Switches(frozenset({Code.SHADOW_MISSING}), (Switch("shadow_missing"),))
    assert Code.SHADOW_MISSING in on and Code.SHADOW_OFFSET not in on
    with pytest.raises(TypeError, match="not a Code member"):
        on.pick("shadow_missing", None, lambda: 1, 0)
    with pytest.raises(ValueError, match="hooked in raycheck.tracer.arithmetic.mistaken"):
        hooks("elsewhere", Code.SHADOW_MISSING)
    with pytest.raises(TypeError, match="is not a mistake's Code"):
        hooks("elsewhere", "shadow_missing")  # type: ignore[arg-type]
    assert HOOKED[Code.SHADOW_MISSING] == "raycheck.tracer.arithmetic.mistaken"


def test_every_entry_names_a_starter_function_and_a_parameter_within_its_range():
    functions = {"PointLight::getIllumination", "Material::shade", "Renderer::traceRay",
                 "Renderer::Render", "Triangle::intersect", "Transform::intersect",
                 "Plane::intersect", "Plane::Plane", "Sphere::intersect"}
    assert len({m.code for m in CATALOGUE}) == len(CATALOGUE)
    for m in CATALOGUE:
        assert m.function in functions, m.code
        # every mistake shows in the color image but one: a jittered image's normal and
        # depth from one sample
        assert m.kinds <= set(KINDS) and ("color" in m.kinds) != (m.code == "jitter_aux_one_sample")
        p = m.parameter
        assert ("{value}" in m.does) == (p is not None), m.code
        if p is not None:
            assert all(p.low <= v <= p.high and v != p.course for v in p.sweep), m.code


def test_what_a_scene_has_decides_which_mistakes_can_show():
    # a plane, a sphere, a transformed mesh, a point and a directional light ...
    scene = load_scene(SHADOWS)
    plain = present(scene, RenderRequest())
    assert plain == {Needs.LIGHT, Needs.POINT_LIGHT, Needs.DIRECTIONAL_LIGHT, Needs.PLANE,
                     Needs.SPHERE, Needs.TRIANGLE, Needs.TRANSFORM}  # ... and no ks, no flags
    assert present(scene, RenderRequest(shadows=True)) == plain | {Needs.SHADOWS}
    codes = {m.code for m in applicable(scene, RenderRequest())}
    assert "falloff_power" in codes and "shadow_offset" not in codes
    assert "specular_half_vector" not in codes  # no material has a ks


def rendered(path: Path, **options) -> dict[str, np.ndarray]:
    opts = RenderOptions(width=24, height=24, kinds=KINDS, **options)
    result = render(load_scene(path), opts)
    return {k: getattr(result, k) for k in KINDS}


@pytest.mark.parametrize("path, flags", [(SHADOWS, {"shadows": True}),
                                         (BOUNCES, {"shadows": True, "bounces": 3}),
                                         # mirrors without -bounces: a chain of no levels
                                         (BOUNCES, {"shadows": True}),
                                         (SHADOWS, {"jitter": True, "filter": True})])
def test_every_mistake_compiled_in_and_none_on_is_the_course_bit_for_bit(path, flags):
    course = rendered(path, **flags)
    every = tuple(MISTAKES)
    compiled = rendered(path, **flags, mistake_kernel=every)
    for kind in KINDS:
        assert np.array_equal(course[kind], compiled[kind], equal_nan=True), kind


def test_an_extra_bounce_without_bounces_is_the_course_at_bounces_one():
    extra = rendered(BOUNCES, shadows=True, mistakes=("reflection_depth=1",))
    course = rendered(BOUNCES, shadows=True, bounces=1)
    for kind in KINDS:
        assert np.array_equal(extra[kind], course[kind], equal_nan=True), kind
    assert not np.array_equal(extra["color"], rendered(BOUNCES, shadows=True)["color"])


def test_one_kernel_serves_every_switch_setting():
    """Renders with the same mistakes compiled in launch the same kernel code whichever are on
    and at whatever parameter: Dr.Jit's kernel history shows no new compilation."""
    from raycheck.tracer.kernel.backend import import_drjit

    dr = import_drjit()
    every = tuple(MISTAKES)
    rendered(SHADOWS, shadows=True, mistake_kernel=every, mistakes=("shadow_offset=0.1",))
    dr.set_flag(dr.JitFlag.KernelHistory, True)
    dr.kernel_history()
    try:
        for on in [("shadow_offset=0.02",), ("falloff_power=1", "shadow_missing"), ()]:
            rendered(SHADOWS, shadows=True, mistake_kernel=every, mistakes=on)
        history = [k for k in dr.kernel_history() if str(k.get("type", "")).endswith("JIT")]
    finally:
        dr.set_flag(dr.JitFlag.KernelHistory, False)
    assert history and all(k.get("cache_hit") for k in history)


def test_shadow_missing_is_the_render_without_shadows_and_falloff_power_two_the_course():
    assert all(np.array_equal(a, b, equal_nan=True) for a, b in zip(
        rendered(SHADOWS, shadows=True, mistakes=("shadow_missing",)).values(),
        rendered(SHADOWS).values()))
    # d^2 is the course's law through another formula: within float rounding of it
    course = rendered(SHADOWS)["color"]
    squared = rendered(SHADOWS, mistakes=("falloff_power=2",))["color"]
    assert np.allclose(course, squared, rtol=1e-5, atol=1e-6)
    assert not np.allclose(course, rendered(SHADOWS, mistakes=("falloff_power=1",))["color"],
                           rtol=1e-3)


def test_jitter_mistakes_are_the_samples_moved_counted_or_one_kept():
    """jitter_fixed=0 is every sample at the (sub-)pixel's corner: the render without -jitter
    (16 equal samples averaged: within float rounding); jitter_samples=4 is the request with
    --samples 4, bit for bit; jitter_aux_one_sample leaves the color image alone and changes
    normals and depth; jitter_centred moves the samples (a different image, same seed)."""
    jittered = {"jitter": True, "seed": 7}
    course = rendered(SHADOWS, **jittered)
    corner = rendered(SHADOWS, **jittered, mistakes=("jitter_fixed=0",))
    plain = rendered(SHADOWS)
    for kind in ("color", "normals"):
        assert np.allclose(corner[kind], plain[kind], rtol=1e-6, atol=1e-6), kind
    four = rendered(SHADOWS, **jittered, mistakes=("jitter_samples=4",))
    requested = rendered(SHADOWS, **jittered, samples=4)
    assert all(np.array_equal(four[k], requested[k], equal_nan=True) for k in KINDS)
    one = rendered(SHADOWS, **jittered, mistakes=("jitter_aux_one_sample",))
    assert np.array_equal(one["color"], course["color"])
    assert not np.allclose(one["normals"], course["normals"])
    centred = rendered(SHADOWS, **jittered, mistakes=("jitter_centred=1",))
    assert not np.allclose(centred["color"], course["color"])


def test_a_sample_loop_that_ends_early_and_a_sum_line_left_out():
    """sample_loop_bound=4 adds up the first 4 of the 16 samples and divides by 16: the
    request with --samples 4 (the same first 4 samples of each sub-pixel's stream) divided by
    4, bit for bit (a power of two); without -jitter, one sample, it changes nothing. A sum
    line left out leaves that image at its start: black, or with the color sum starting at
    (1, 0, 0), 1/1 red everywhere; the other kinds are the course's."""
    jittered = {"jitter": True, "seed": 7}
    bound = rendered(SHADOWS, **jittered, mistakes=("sample_loop_bound.constant=4",))
    four = rendered(SHADOWS, **jittered, samples=4)
    assert all(np.array_equal(bound[k], four[k] / np.float32(4), equal_nan=True)
               for k in KINDS)
    course = rendered(SHADOWS)
    unbound = rendered(SHADOWS, mistakes=("sample_loop_bound.constant=4",))
    assert all(np.array_equal(unbound[k], course[k], equal_nan=True) for k in KINDS)
    no_depth = rendered(SHADOWS, mistakes=("depth_add.deleted",))
    assert not no_depth["depth"].any()
    assert all(np.array_equal(no_depth[k], course[k], equal_nan=True) for k in KINDS[:2])
    red = rendered(SHADOWS, mistakes=("color_add.deleted", "color_start_r.constant=1"))
    assert np.array_equal(red["color"], np.broadcast_to(np.float32([1, 0, 0]),
                                                        course["color"].shape))
    assert all(np.array_equal(red[k], course[k], equal_nan=True) for k in KINDS[1:])


def test_a_jittered_sum_left_undivided_or_multiplied_by_its_samples():
    """color_mean.deleted: the color image is the sum of a pixel's 16 samples, the course's
    mean times 16; color_mean.times: times 16 again; bit for bit (powers of two); the other
    kinds are the course's, and without -jitter (one sample) nothing changes."""
    jittered = {"jitter": True, "seed": 7}
    course = rendered(SHADOWS, **jittered)
    summed = rendered(SHADOWS, **jittered, mistakes=("color_mean.deleted",))
    assert np.array_equal(summed["color"], course["color"] * np.float32(16))
    assert all(np.array_equal(summed[k], course[k], equal_nan=True) for k in KINDS[1:])
    times = rendered(SHADOWS, **jittered, mistakes=("normals_mean.times",))
    assert np.array_equal(times["normals"], course["normals"] * np.float32(256))
    plain = rendered(SHADOWS)
    unjittered = rendered(SHADOWS, mistakes=("color_mean.deleted", "depth_mean.times"))
    assert all(np.array_equal(unjittered[k], plain[k], equal_nan=True) for k in KINDS)


def test_the_readme_counts_the_catalogue_and_the_generated_mistakes():
    text = " ".join((REPO / "README.md").read_text().split())
    said = re.search(r"a catalogue of (\d+),.* (\d+) more that mutation operators generate at "
                     r"(\d+) sites", text)
    assert said is not None
    assert tuple(map(int, said.groups())) == (len(CATALOGUE), len(GENERATED),
                                              len({m.code.partition(".")[0] for m in GENERATED}))


def test_mistakes_are_course_mode_only():
    with pytest.raises(OptionError, match="mistakes are switches of course mode"):
        RenderOptions(mode="robust", mistakes=("shadow_missing",))
    with pytest.raises(OptionError, match="unknown mistake 'nope'"):
        RenderOptions(mistake_kernel=("nope",))


def test_the_command_line_renders_with_mistakes_and_refuses_unknown_ones(tmp_path: Path):
    def run(*extra: str) -> subprocess.CompletedProcess:
        return subprocess.run([sys.executable, "-m", "raycheck.tracer", "-input", str(SHADOWS),
                               "-size", "16", "16", "-shadows", "-output",
                               str(tmp_path / "a.png"), "--quiet", *extra],
                              capture_output=True, text=True, timeout=300)

    ok = run("--mistake", "shadow_offset=0.1", "--mistake", "falloff_power=1,light_reversed")
    assert ok.returncode == 0 and (tmp_path / "a.png").is_file(), ok.stderr
    bad = run("--mistake", "shadow_offset=7")
    assert bad.returncode == 2
    assert bad.stderr.strip().splitlines() == [
        "python -m raycheck.tracer: error: mistake shadow_offset: its offset must be in [0, 1]"]
