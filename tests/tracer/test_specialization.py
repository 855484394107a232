"""Kernels hold only what a scene and its flags need: the code paths that are not needed are
never traced (counted by wrapping them while a tiny image renders)."""
from __future__ import annotations

from collections import Counter
from pathlib import Path

import numpy as np
import pytest

from raycheck.tracer.accel.intersect import Intersector
from raycheck.tracer.options import RenderOptions
from raycheck.tracer.render import Renderer
from raycheck.tracer.scene import parse_scene_text
from raycheck.tracer.shade.background import Background
from raycheck.tracer.shade.shading import Shader

HEAD = "PerspectiveCamera { center 0 0 10 direction 0 0 -1 up 0 1 0 angle 30 }\n"
LIGHTS = ("Lights { numLights 2 DirectionalLight { direction 0 0 -1 color 1 1 1 } "
          "PointLight { position 0 3 3 color 1 1 1 falloff 1 } }\n")
MATTE = "Materials { numMaterials 1 Material { diffuseColor 1 0 0 specularColor 0.05 0 0 } }\n"
MIRROR = "Materials { numMaterials 1 Material { specularColor 0.5 0.5 0.5 } }\n"
SPHERE = "Group { numObjects 1 MaterialIndex 0 Sphere { center 0 0 0 radius 1 } }\n"


@pytest.fixture()
def traced(monkeypatch) -> Counter:
    calls: Counter = Counter()
    for cls, name in ((Intersector, "occluded"), (Intersector, "_triangles"),
                      (Shader, "_mirror_chain"), (Background, "_cube_lookup")):
        original = getattr(cls, name)

        def wrapper(self, *a, _orig=original, _name=name, **k):
            calls[_name] += 1
            return _orig(self, *a, **k)

        monkeypatch.setattr(cls, name, wrapper)
    return calls


def render(text: str, **opts) -> None:
    Renderer(parse_scene_text(text, Path("/x/s.txt")), RenderOptions(4, 4, **opts)).render()


def test_no_shadow_rays_without_the_flag(traced: Counter):
    render(HEAD + LIGHTS + MATTE + SPHERE, bounces=3)
    assert traced == Counter()


def test_one_shadow_query_per_light_with_the_flag(traced: Counter):
    render(HEAD + LIGHTS + MATTE + SPHERE, shadows=True)
    assert traced == Counter(occluded=2)


def test_no_shadow_rays_without_lights(traced: Counter):
    render(HEAD + MATTE + SPHERE, shadows=True)
    assert traced == Counter()


def test_reflection_loop_only_with_a_mirror_and_bounces(traced: Counter):
    render(HEAD + LIGHTS + MIRROR + SPHERE)  # mirror but no -bounces
    render(HEAD + LIGHTS + MATTE + SPHERE, bounces=4)  # bounces but |ks| <= 0.1
    assert traced == Counter()
    render(HEAD + LIGHTS + MIRROR + SPHERE, bounces=4)
    assert traced == Counter(_mirror_chain=1)


def test_mesh_and_cube_map_code_only_when_present(traced: Counter, tmp_path: Path):
    from PIL import Image

    render(HEAD + LIGHTS + MATTE + SPHERE)
    assert traced == Counter()
    tri = ("Group { numObjects 1 MaterialIndex 0 "
           "Triangle { vertex0 0 0 0 vertex1 1 0 0 vertex2 0 1 0 } }\n")
    render(HEAD + LIGHTS + MATTE + tri)
    assert traced == Counter(_triangles=1)
    for name in ("left", "right", "up", "down", "front", "back"):
        Image.fromarray(np.zeros((2, 2, 3), np.uint8)).save(tmp_path / f"{name}.png")
    scene = parse_scene_text(HEAD + f"Background {{ cubeMap {tmp_path} }}\n" + MATTE + SPHERE,
                             tmp_path / "s.txt")
    Renderer(scene, RenderOptions(4, 4)).render()
    assert traced == Counter(_triangles=1, _cube_lookup=1)


def test_only_requested_images_are_computed():
    scene = parse_scene_text(HEAD + LIGHTS + MATTE + SPHERE, Path("/x/s.txt"))
    r = Renderer(scene, RenderOptions(4, 4, kinds=("depth",))).render()
    assert r.color is None and r.normals is None and r.depth.shape == (4, 4)


def test_a_size_1_array_from_numpy_gives_one_kernel_wherever_numpy_put_it():
    """from_numpy: the same kernel IR for a size-1 array at any address (Dr.Jit reads arrays
    from numpy's memory and loads a size-1 one with `align 4` only at 64-byte aligned ones, else
    `align 1`: a second compiled version of a cached kernel, in some processes)."""
    from raycheck.tracer.kernel.backend import from_numpy, import_drjit
    from raycheck.tracer.kernel.vecmath import make_types

    dr, T = import_drjit(), make_types()
    buf = np.zeros(256, np.uint8)
    start = (-buf.ctypes.data) % 64
    irs = set()
    dr.set_flag(dr.JitFlag.KernelHistory, True)
    try:
        for shift in (0, 4, 8, 16, 32):
            value = buf[start + shift:start + shift + 4].view(np.float32)
            value[0] = 3.0
            x = dr.arange(T.Float, 16) * dr.gather(T.Float, from_numpy(T.Float, value),
                                                   T.UInt32(0))
            dr.kernel_history()  # clears the history
            dr.eval(x)
            irs |= {k["ir"].getvalue() if hasattr(k["ir"], "getvalue") else str(k["ir"])
                    for k in dr.kernel_history() if k["type"] == dr.KernelType.JIT}
            assert x.numpy()[2] == 6.0
    finally:
        dr.set_flag(dr.JitFlag.KernelHistory, False)
    assert len(irs) == 1


def _loop_condition_blocks(ir: str) -> dict[str, str]:
    """Each symbolic loop's condition block in Dr.Jit's LLVM IR: from its `l_N_cond:` label to
    the branch into `l_N_body`."""
    import re

    blocks = {}
    for m in re.finditer(r"^(l_\d+)_cond:\n(.*?)^\s*br i1 [^\n]*label %\1_body", ir,
                         re.MULTILINE | re.DOTALL):
        blocks[m.group(1)] = m.group(2)
    return blocks


def test_the_mirror_loop_body_is_recorded_once():
    """backend.recording_kernel: with Dr.Jit's OptimizeLoops on, the mirror chain's body (its
    writes to the per-level local buffers, and the shading they depend on) was also emitted
    into the loop's condition block and ran twice per level. A condition block holds the loop
    test only: no memory write, no gather."""
    from raycheck.tracer.kernel.backend import import_drjit

    dr = import_drjit()
    group = ("Group { numObjects 2 MaterialIndex 0 Sphere { center 0 0 0 radius 1 } "
             "Triangle { vertex0 -3 -1 -2 vertex1 3 -1 -2 vertex2 0 3 -2 } }\n")
    scene = parse_scene_text(HEAD + LIGHTS + MIRROR + group, Path("/x/s.txt"))
    dr.set_flag(dr.JitFlag.KernelHistory, True)
    try:
        dr.kernel_history()  # clears the history
        Renderer(scene, RenderOptions(4, 4, bounces=2, shadows=True)).render()
        irs = [k["ir"].getvalue() for k in dr.kernel_history()
               if k["type"] == dr.KernelType.JIT and k.get("ir") is not None]
    finally:
        dr.set_flag(dr.JitFlag.KernelHistory, False)
    blocks = {name: body for ir in irs for name, body in _loop_condition_blocks(ir).items()}
    assert len(blocks) >= 5  # the mirror chain, its fold, BVH loops (closest, shadows)
    for name, body in blocks.items():
        assert "scatter" not in body and "store " not in body and "gather" not in body, name


def _kernels_and_image(text: str, **opts) -> tuple[list[str], "object"]:
    """The hashes of the kernels a 4x4 render launches, in order, and its color image."""
    from raycheck.tracer.kernel.backend import import_drjit

    dr = import_drjit()
    dr.set_flag(dr.JitFlag.KernelHistory, True)
    try:
        dr.kernel_history()  # clears the history
        image = Renderer(parse_scene_text(text, Path("/x/s.txt")),
                         RenderOptions(4, 4, **opts)).render().color
        hashes = [k["hash"] for k in dr.kernel_history() if k["type"] == dr.KernelType.JIT]
    finally:
        dr.set_flag(dr.JitFlag.KernelHistory, False)
    return hashes, image


def test_light_camera_and_background_values_are_read_at_run_time():
    """uniforms.py: a scene whose camera, light colors, point light, falloff, background color
    and ambient light changed renders a different image with the same kernels (no compiling);
    geometry and a directional light's direction are literals, so changing them gives other
    kernels."""
    group = ("Group { numObjects 2 MaterialIndex 0 Sphere { center 0 0 0 radius 1 } "
             "Triangle { vertex0 -3 -1 -2 vertex1 3 -1 -2 vertex2 0 3 -2 } }\n")
    background = "Background { color 0.1 0.2 0.3 ambientLight 0.2 0.2 0.2 }\n"
    base = HEAD + background + LIGHTS + MIRROR + group
    flags = dict(bounces=2, shadows=True)
    hashes, image = _kernels_and_image(base, **flags)
    edits = [("center 0 0 10 direction 0 0 -1 up 0 1 0 angle 30",
              "center 0.5 0 9 direction -0.1 0 -1 up 0.1 1 0 angle 40"),
             ("direction 0 0 -1 color 1 1 1", "direction 0 0 -1 color 0.5 1 0.2"),
             ("position 0 3 3 color 1 1 1 falloff 1", "position 1 2 4 color 1 0 1 falloff 0.5"),
             ("color 0.1 0.2 0.3 ambientLight 0.2 0.2 0.2",
              "color 0.3 0.1 0 ambientLight 0.4 0 0.1")]
    for old, new in edits:
        assert old in base
        again, edited = _kernels_and_image(base.replace(old, new), **flags)
        assert again == hashes, new
        assert not np.array_equal(edited, image), new
    for old, new in [("radius 1", "radius 0.5"),
                     ("direction 0 0 -1 color 1 1 1", "direction 0 -1 -1 color 1 1 1")]:
        other, _ = _kernels_and_image(base.replace(old, new), **flags)
        assert other != hashes, new


def test_the_forced_ambient_light_keeps_a_subnormal_diffuse_color():
    """A scene without lights shades with the ambient light forced to 1 (spec §6): color =
    1 * kd, in the course's C a subnormal kd as it is. Kept literal (uniforms.py): read at run
    time, Dr.Jit's worker threads flushed the product to 0."""
    text = (HEAD + "Materials { numMaterials 1 Material { diffuseColor 1e-40 2e-40 0 } }\n"
            "Group { numObjects 1 MaterialIndex 0 Sphere { center 0 0 0 radius 3 } }\n")
    color = Renderer(parse_scene_text(text, Path("/x/s.txt")), RenderOptions(8, 8)).render().color
    assert color[4, 4].tolist() == [float(np.float32(1e-40)), float(np.float32(2e-40)), 0.0]
