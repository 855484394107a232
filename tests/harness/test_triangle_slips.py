"""Slips in the starter-shaped solution's Triangle::intersect (a real C++ program, built with
CMake), reproduced by the generated mistakes at its sites: on a mesh, whose course octree
tests only the triangles of the leaves a ray visits, and on a lone triangle."""
from __future__ import annotations

import shutil
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO / "tests"))
sys.path.insert(0, str(REPO / "tests" / "harness"))

from solution import Edit, build_solution, copy_solution  # noqa: E402
from test_causes import checked, first_failing  # noqa: E402

from raycheck.harness.renderers.command import CommandRenderer  # noqa: E402

SCENES = (REPO / "scenes" / "course" / "smooth_mesh.txt",
          REPO / "scenes" / "features" / "triangle.txt")


@pytest.mark.full  # two builds of the solution, cached after the first run
@pytest.mark.skipif(shutil.which("cmake") is None, reason="cmake is not installed")
@pytest.mark.parametrize("slip, cause", [
    # the rejection's return left out: every hit of the triangle's plane is taken; on the
    # mesh only where a leaf the ray visits holds the triangle (all of them, tested brute
    # force, would cover more of the image)
    (Edit("src/Object3D.cpp", "u + v > 1) {\n        return false;",
          "u + v > 1) {\n        /*return false;*/"), "triangle_inside.deleted"),
    # barycentric coordinates measured from v1: u one less
    (Edit("src/Object3D.cpp", "(r.pointAtParameter(t) - _v[0])",
          "(r.pointAtParameter(t) - _v[1])"), "triangle_origin.index=1"),
])
def test_a_triangle_slip_is_reproduced_on_a_mesh_and_a_lone_triangle(tmp_path: Path, slip,
                                                                      cause):
    program = CommandRenderer([str(build_solution(copy_solution(tmp_path / "src", (slip,))))])
    for scene in SCENES:
        top = first_failing(checked(program, scene, "plain", size=48)).findings[0]
        assert top.code == f"cause:{cause.partition('=')[0]}", (scene.name, top)
        assert "the reference reproduces your images" in top.message, (scene.name, top)
        assert top.message.endswith(f"--mistake {cause}"), (scene.name, top)
