"""A -filter kernel of the program's own (harness/judge/filter_fit.py, the cause search's
_kernel): its weights fitted by least squares on the reference rendered at three times the
size, written as whole numbers over a divisor, and switched on at the filter's sites as one
cause. Expected kernels are worked out by hand from the C++ they stand for."""
from __future__ import annotations

import json
import shutil
import sys
from pathlib import Path

import numpy as np
import pytest

from raycheck.harness.diagnosis.causes import kernel_switches, own_kernel
from raycheck.harness.judge.filter_fit import COURSE_FILTER, WrittenKernel, fit_kernel, written
from raycheck.tracer.mistakes import Switch

REPO = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO / "tests"))
sys.path.insert(0, str(REPO / "tests" / "harness"))

from solution import Edit, build_solution, copy_solution  # noqa: E402
from test_causes import checked, first_failing, mistaken  # noqa: E402
from test_parallel import quietly  # noqa: E402

from raycheck.harness.cli.check import main as check_main  # noqa: E402

JITTER_FILTER = REPO / "scenes" / "features" / "jitter_filter.txt"
BOX = WrittenKernel(((1, 1, 1), (1, 1, 1), (1, 1, 1)), 9)
# the box as switches: the five weights that are not 1 in the course's K, and the divisor
BOX_SWITCHES = (Switch("filter_weight_01.constant", 1.0), Switch("filter_weight_10.constant", 1.0),
                Switch("filter_weight_11.constant", 1.0), Switch("filter_weight_12.constant", 1.0),
                Switch("filter_weight_21.constant", 1.0), Switch("filter_divisor.constant", 9.0))
BOX_SAID = ("Renderer::Render: your program's -filter kernel is [1 1 1; 1 1 1; 1 1 1]/9, not "
            "the course's [1 2 1; 2 4 2; 1 2 1]/16")


def test_written_kernels_are_whole_weights_over_the_divisor_that_changes_least():
    assert written(np.full((3, 3), 1 / 9)) == BOX
    # twice the course's: its weights over 8 (one constant changed), not each doubled
    assert written(2 * COURSE_FILTER) == WrittenKernel(((1, 2, 1), (2, 4, 2), (1, 2, 1)), 8)
    # the loop over a row's taps ending after the first: the left column, and a fit's noise
    left = np.array([[1, 0, 0], [2, 0, 0], [1, 0, 0]]) / 16 + 0.004 * np.sin(np.arange(9)
                                                                            ).reshape(3, 3)
    assert written(left) == WrittenKernel(((1, 0, 0), (2, 0, 0), (1, 0, 0)), 16)
    # a sixty-fourth beside sixteenths: no divisor up to 32 makes both whole within 0.1
    sixty_fourth = COURSE_FILTER.copy()
    sixty_fourth[0, 0] = 1 / 64
    assert written(sixty_fourth) is None
    assert written(np.zeros((3, 3))) is None


def test_the_fit_recovers_a_kernel_from_the_blocks_it_weighs():
    """A candidate made from random 3x3 blocks with the box: the fit gives 1/9 each."""
    rng = np.random.default_rng(7)
    big = rng.integers(0, 200, size=(36, 36, 3))
    blocks = np.stack([big[r::3, c::3] for r in range(3) for c in range(3)], axis=-1)
    got = np.rint(blocks.mean(axis=-1)).astype(np.int32)
    fit = fit_kernel(big, got)
    assert fit is not None and fit.rms < 0.5
    assert written(fit.weights) == BOX
    assert fit_kernel(big[:33], got) is None  # not three times the size


def test_a_kernel_switches_its_sites_bottom_row_first_and_is_said_whole():
    assert kernel_switches(BOX) == BOX_SWITCHES
    # the fit's rows are top-down; the course's K[0] is the bottom row of a block
    top = kernel_switches(WrittenKernel(((1, 2, 1), (2, 4, 2), (0, 0, 0)), 16))
    assert top == (Switch("filter_weight_00.constant", 0.0),
                   Switch("filter_weight_01.constant", 0.0),
                   Switch("filter_weight_02.constant", 0.0))
    assert own_kernel(top) == ("Renderer::Render: your program's -filter kernel is "
                               "[1 2 1; 2 4 2; 0 0 0]/16, not the course's [1 2 1; 2 4 2; "
                               "1 2 1]/16")
    assert own_kernel(BOX_SWITCHES) == BOX_SAID
    assert own_kernel(BOX_SWITCHES[:1]) is None  # one constant: that constant's own finding
    assert own_kernel(BOX_SWITCHES[:1] + (Switch("shadow_missing"),)) is None


def test_a_kernel_whose_weights_no_site_takes_switches_nothing():
    """A fit of images no kernel makes (each tap's weight added to it, not multiplied)
    gives weights past the sites' range [-4, 8]: the search tried them and the tracer refused
    the switch, which ended the whole search with no finding at all."""
    assert kernel_switches(WrittenKernel(((60, 1, 1), (1, 1, 1), (1, 1, 1)), 16)) == ()
    assert kernel_switches(WrittenKernel(((8, 2, 1), (2, 4, 2), (1, 2, -4)), 16)) == (
        Switch("filter_weight_02.constant", -4.0), Switch("filter_weight_20.constant", 8.0))


def test_the_tracer_with_a_box_filter_is_found_by_its_kernel():
    """Six constants at once: beyond the search's pairs and triples, found by the fit."""
    result = checked(mistaken(*BOX_SWITCHES), JITTER_FILTER, "filter")
    top = first_failing(result).findings[0]
    assert top.code == "cause:filter_divisor.constant"
    assert top.message.startswith(f"{BOX_SAID}. With it, the reference reproduces your "
                                  "images: 100.0% of pixels match"), top


@pytest.mark.full  # two builds of the solution, cached after the first run
@pytest.mark.skipif(shutil.which("cmake") is None, reason="cmake is not installed")
@pytest.mark.parametrize("slip, said, jittered", [
    ((Edit("src/Renderer.cpp", "{{1, 2, 1}, {2, 4, 2}, {1, 2, 1}}",
           "{{1, 1, 1}, {1, 1, 1}, {1, 1, 1}}"),
      Edit("src/Renderer.cpp", "sum / 16.0f", "sum / 9.0f")), BOX_SAID, True),
    # the loop over a row's taps ends after the first: each row's left sub-pixel only (the
    # first row's starts at the second tap, so it has none past the one summed before). Its
    # -jitter -filter depth is not the kernel's: a pixel whose samples miss sums depths past
    # float's range (inf), which the program's skipped taps leave out and the tracer's zero
    # weights make 0 * inf = NaN, as a program's zero in its weights would
    ((Edit("src/Renderer.cpp", "i < 3; ++i", "i < 1; ++i"),),
     "Renderer::Render: your program's -filter kernel is [1 0 0; 2 0 0; 1 0 0]/16, not the "
     "course's [1 2 1; 2 4 2; 1 2 1]/16", False),
])
def test_a_cpp_program_with_its_own_kernel_is_reproduced(tmp_path: Path, slip, said,
                                                         jittered):
    """`raycheck check` of the starter-shaped solution with a box filter, and with the taps'
    loop one short: every failing -filter image reproduced by the kernel, and the box's
    failing -jitter -filter images a likely draw with it (the -filter case's cause, its
    prior); the short loop's only located there."""
    program = build_solution(copy_solution(tmp_path / "src", slip))
    out = tmp_path / "out"
    assert quietly(check_main, ["--renderer", str(program), "features/jitter_filter", "--out",
                                str(out), "--size", "48", "48", "--features",
                                "filter,jitter+filter", "--strict", "--quiet"]) == 1
    report = json.loads((out / "check.json").read_text())
    failing = {(c["feature"], c["kind"]): c["findings"][0]["message"]
               for c in report["cases"] if c["verdict"] == "fail"}
    assert {f for f, _ in failing} == {"filter", "jitter+filter"}
    for (feature, kind), message in failing.items():
        if feature == "jitter+filter" and not jittered:
            assert message.startswith("Renderer::Render: no known mistake reproduces this "
                                      f"image; the evidence points here: your {kind} image "
                                      "differs only with -jitter"), (kind, message)
            continue
        how = ("the reference reproduces your images" if feature == "filter"
               else "your image is a likely draw of the reference's distribution")
        assert message.startswith(f"{said}. With it, {how}"), (feature, kind, message)
