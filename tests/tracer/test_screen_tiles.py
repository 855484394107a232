"""Camera rays' closest hits from screen tiles (tracer/accel/screen_tiles.py): the lists hold what a
ray can hit, and a render with them is the BVH's render bit for bit."""
from __future__ import annotations

import glob
from pathlib import Path

import numpy as np
import pytest
from random_soup import random_triangles, triangle_lines

import raycheck.tracer.render as render_module
from raycheck.tracer.accel.flat_scene import TriangleSoup
from raycheck.tracer.accel.screen_tiles import MAX_BEHIND, screen_tiles
from raycheck.tracer.options import RenderOptions
from raycheck.tracer.render import Renderer
from raycheck.tracer.scene import load_scene
from raycheck.tracer.scene.parser import parse_scene_text
from raycheck.tracer.shade.camera import CameraFrame

REPO = Path(__file__).resolve().parents[2]
F32 = np.float32
# eye at 0 looking down -z, 90 degrees: forward = (0, 0, -1) (dist 1), right x, up y
FRAME = CameraFrame(np.zeros(3, F32), np.array([0, 0, -1], F32), np.array([1, 0, 0], F32),
                    np.array([0, 1, 0], F32))


def soup(triangles) -> TriangleSoup:
    v = np.array(triangles, F32).reshape(-1, 3, 3)
    n = len(v)
    return TriangleSoup(v, np.zeros_like(v), np.zeros(n, np.uint32),
                        np.arange(n, dtype=np.uint32), np.full(n, 0xFFFFFFFF, np.uint32))


def lists(tiles) -> dict[int, list[int]]:
    s = tiles.starts
    return {k: tiles.triangles[s[k]:s[k + 1]].tolist() for k in range(len(s) - 1)
            if s[k + 1] > s[k]}


def test_a_triangle_is_listed_in_the_tiles_its_projection_reaches_with_the_margin():
    # at z = -1, ndc = (x, y): x from -0.1 to 0.1 is sub-pixel (ndc + 1) * 15/2 = 6.75..8.25;
    # lanes x = floor(6.75 - margin - 1) = 4 .. floor(8.25 + margin) = 9 (margin 1.00016),
    # columns 1..2; rows likewise (from the top: (15 - 9) // 4 = 1 .. (15 - 4) // 4 = 2)
    tris = soup([[-0.1, -0.1, -1], [0.1, -0.1, -1], [0, 0.1, -1]])
    tiles = screen_tiles(FRAME, tris, [], np.array([0]), 16, 16)
    assert tiles.columns == 4
    assert lists(tiles) == {5: [0], 6: [0], 9: [0], 10: [0]}


def test_lists_hold_device_indices_and_skip_what_lies_off_screen_or_behind():
    tris = soup([[-0.1, -0.1, -1], [0.1, -0.1, -1], [0, 0.1, -1],    # centre
                 [5, 5, -1], [6, 5, -1], [5, 6, -1],                  # off screen
                 [-0.1, -0.1, 1], [0.1, -0.1, 1], [0, 0.1, 1]])       # wholly behind the eye
    tiles = screen_tiles(FRAME, tris, [], np.array([7, 3, 5]), 16, 16)
    assert lists(tiles) == {5: [7], 6: [7], 9: [7], 10: [7]}


def test_a_triangle_reaching_behind_the_eye_is_in_every_tile():
    tris = soup([[-0.1, -0.1, -1], [0.1, -0.1, -1], [0, 0.1, -1],
                 [-1, 0, 1], [1, 0, 1], [0, 0, -1]])  # crosses the eye's plane
    tiles = screen_tiles(FRAME, tris, [], np.array([0, 1]), 16, 16)
    got = lists(tiles)
    assert set(got) == set(range(16))
    assert all(got[k] == ([0, 1] if k in (5, 6, 9, 10) else [1]) for k in got)


@pytest.mark.parametrize("case", ["nan vertex", "one column", "many behind", "long lists",
                                  "nothing on screen", "too many in all"])
def test_where_the_lists_cannot_be_trusted_or_cost_more_the_bvh_answers(case, monkeypatch):
    size = (16, 16)
    tri = [[-0.1, -0.1, -1], [0.1, -0.1, -1], [0, 0.1, -1]]
    if case == "nan vertex":
        tris = soup([[[np.nan, 0, -1], [1, 0, -1], [0, 1, -1]]])
    elif case == "one column":
        tris, size = soup([tri]), (1, 16)  # ndc = 2 * (x / 0) - 1
    elif case == "many behind":
        tris = soup([[[-1, 0, 1], [1, 0, 1], [0, 0, -1]]] * (MAX_BEHIND + 1))
    elif case == "too many in all":  # the centre triangle's 4 entries, over a total of 3
        import raycheck.tracer.accel.screen_tiles as tiles_module

        monkeypatch.setattr(tiles_module, "MAX_TOTAL", 3)
        tris = soup([tri])
    elif case == "long lists":  # 300 screen-sized triangles: 300 entries a 4x4 tile
        tris = soup([[[-1, -1, -1], [1, -1, -1], [0, 1, -1]]] * 300)
    else:
        tris = soup([[[5, 5, -1], [6, 5, -1], [5, 6, -1]]])
    assert screen_tiles(FRAME, tris, [], np.arange(len(tris)), *size) is None


def _pair(scene, opts: RenderOptions, monkeypatch) -> tuple[Renderer, Renderer]:
    """A render with the tiles (where the renderer makes them) and one through the BVH."""
    with_tiles = Renderer(scene, opts)
    monkeypatch.setattr(render_module, "screen_tiles", lambda *a, **k: None)
    bvh = Renderer(scene, opts)
    monkeypatch.undo()
    return with_tiles, bvh


def _same_bits(a, b) -> None:
    for kind in ("color", "normals", "depth"):
        x, y = getattr(a, kind), getattr(b, kind)
        np.testing.assert_array_equal(x.view(np.uint32), y.view(np.uint32), err_msg=kind)


CONFIGS = [dict(width=37, height=20),
           dict(width=64, height=48, bounces=3, shadows=True),
           dict(width=33, height=31, jitter=True, filter=True, samples=4, seed=3),
           dict(width=162, height=121, bounces=1)]  # large enough for the meshes' lists


def test_bundled_scenes_render_the_same_bits_with_tiles_as_through_the_bvh(monkeypatch,
                                                                          full_run):
    """Every bundled scene in the full run (the quick run: the course scenes, whose meshes
    are where the tiles are used), at sizes that are not multiples of 4, with -jitter -filter
    (samples up to a sub-pixel off their lane's) and with secondary rays (which keep the
    BVH)."""
    pattern = "scenes/**/*.txt" if full_run else "scenes/course/*.txt"
    used = 0
    for path in sorted(glob.glob(str(REPO / pattern), recursive=True)):
        scene = load_scene(Path(path))
        for cfg in CONFIGS:
            opts = RenderOptions(kinds=("color", "normals", "depth"), depth_min=0.0,
                                 depth_max=20.0, **cfg)
            with_tiles, bvh = _pair(scene, opts, monkeypatch)
            used += with_tiles.tiles is not None
            assert bvh.tiles is None
            _same_bits(with_tiles.render(), bvh.render())
    # arch, axes and cube_directional in every config; cubemap_mesh's and smooth_mesh's lists
    # are short enough (MAX_ENTRIES) only in the largest
    assert used >= 14


def test_random_triangles_render_the_same_bits_with_tiles_as_through_the_bvh(monkeypatch):
    """Seeded random soups around the eye: triangles in front, across the eye's plane and
    behind it, thin and large, some sharing edges, in transformed groups, seen through
    random cameras; jittered. Where the tiles are made, the image is the BVH's."""
    rng = np.random.default_rng(17)
    made = 0
    for trial in range(24):
        lines = triangle_lines(random_triangles(rng))
        group = "\n".join(lines)
        if trial % 3 == 0:
            group = ("Transform { YRotate %d Scale 1 %f 1 Group { numObjects %d MaterialIndex 0 "
                     "%s } }" % (rng.integers(0, 90), rng.uniform(0.5, 2), len(lines), group))
            count = 1
        else:
            count = len(lines)
        d = rng.normal(0, 1, 3) + (0, 0, -2)
        text = ("PerspectiveCamera { center %f %f %f direction %f %f %f up 0 1 0 angle %d }\n"
                % (*rng.normal(0, 0.5, 3), *d, rng.integers(20, 120))
                + "Lights { numLights 1 DirectionalLight { direction 0.3 -1 -0.5 color 1 1 1 } }\n"
                + "Materials { numMaterials 1 Material { diffuseColor 0.8 0.5 0.2 "
                + "specularColor 0.5 0.5 0.5 shininess 8 } }\n"
                + "Group { numObjects %d MaterialIndex 0 %s }\n" % (count, group))
        scene = parse_scene_text(text, Path("random.txt"))
        opts = RenderOptions(width=23, height=18, jitter=True, samples=3, seed=trial,
                             shadows=True, bounces=1, kinds=("color", "normals", "depth"),
                             depth_min=0.0, depth_max=10.0)
        with_tiles, bvh = _pair(scene, opts, monkeypatch)
        made += with_tiles.tiles is not None
        _same_bits(with_tiles.render(), bvh.render())
    assert made >= 16
