"""The shipped reference distributions (harness/storage/shipped.py): lossless, found exactly for
the jittered cases of a check of the bundled scenes, and what the tracer renders now, byte for
byte (all of them in the full run, as CI runs it; the smallest in the quick one)."""
from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import pytest

from raycheck.harness.cases import Case
from raycheck.harness.provenance import vector_isa
from raycheck.harness.renderers import Renderer
from raycheck.harness.storage import shipped
from raycheck.harness.storage.distribution import (
    REFERENCE_SEED,
    reference_distribution,
    render_realisations,
)

TOOLS = Path(__file__).resolve().parents[2] / "tools"
# Mitsuba's bytes that may differ on another vector instruction set, a share of a kind's: six
# times the most measured, AVX2 against the AVX-512 data (8 of a case's 3,145,728 color values,
# 5 of its 1,048,576 depths: edges that one sample in millions grazes, depths' last bits)
OTHER_ISA_SHARE = 3e-5


def test_encoding_is_lossless_and_keeps_only_the_varying_pixels():
    rng = np.random.default_rng(7)
    b = np.full((5, 3, 4, 3), 200, np.uint8)
    b[:, 1, 2, 0] = rng.integers(0, 256, 5, dtype=np.uint8)  # one channel of one pixel
    b[3, 2, 0] = (0, 255, 7)  # one realisation differs at another
    b[0, 0, 0, 2] = 199  # the first realisation alone: every other one differs from it
    poisoned = np.zeros((3, 4), np.int64)
    poisoned[2, 3] = 5
    arrays = shipped.encode(b, poisoned)
    assert arrays["where"].tolist() == [0, 6, 8]  # flat indices (y * 4 + x)
    assert arrays["steps"].shape == (3, 3, 5) and arrays["steps"].dtype == np.uint8
    assert arrays["steps"][0, 2].tolist() == [0, 1, 1, 1, 1]  # 200 - 199
    assert arrays["steps"][2, 1].tolist() == [0, 0, 0, 55, 0]  # 255 - 200
    assert np.array_equal(shipped.decode(arrays["first"], arrays["where"], arrays["steps"], 5), b)
    assert arrays["poisoned"][2, 3] == 5


def test_a_file_is_read_only_under_its_key_and_size(tmp_path, monkeypatch):
    b = np.arange(2 * 2 * 3 * 3, dtype=np.uint8).reshape(2, 2, 3, 3) % 4
    bad = np.zeros((2, 3), np.int64)
    monkeypatch.setattr(shipped, "FOLDER", tmp_path)
    shipped._index.cache_clear()
    shipped.write(tmp_path / "a.npz", {"color": (b, bad)}, "k1")
    (tmp_path / shipped.INDEX).write_text(json.dumps({"k1": "a.npz", "k2": "a.npz",
                                                      "k3": "gone.npz"}))
    try:
        got = shipped.read("k1", ("color",), (2, 3), 2)
        assert got is not None and np.array_equal(got["color"][0], b)
        assert shipped.read("k2", ("color",), (2, 3), 2) is None  # the file says k1
        assert shipped.read("k1", ("color",), (3, 2), 2) is None  # another size
        assert shipped.read("k1", ("color",), (2, 3), 3) is None  # another K
        assert shipped.read("k1", ("depth",), (2, 3), 2) is None  # a kind it lacks
        assert shipped.read("k3", ("color",), (2, 3), 2) is None  # no such file
        whole = (tmp_path / "a.npz").read_bytes()
        for damaged in (b"PK\x03\x04 damaged",  # not a zip file
                        whole.replace(b"\x5d\x00", b"\x00\xff", 1)):  # an LZMA header's bytes
            (tmp_path / "a.npz").write_bytes(damaged)
            assert shipped.read("k1", ("color",), (2, 3), 2) is None
        (tmp_path / shipped.INDEX).write_text(json.dumps({"k1": 5}))
        shipped._index.cache_clear()
        assert shipped.read("k1", ("color",), (2, 3), 2) is None
    finally:
        shipped._index.cache_clear()


@pytest.mark.parametrize("edit", ["where_outside", "where_negative", "poisoned_over_k",
                                  "one_channel"])
def test_an_edited_file_is_not_read(edit, tmp_path, monkeypatch):
    b = np.zeros((2, 2, 3, 3), np.uint8)
    b[1, 0, 0] = 9
    arrays = {"key": np.array("k1")} | {f"color_{n}": a for n, a in
                                         shipped.encode(b, np.zeros((2, 3))).items()}
    if edit == "where_outside":
        arrays["color_where"] = np.array([6], np.int32)
    elif edit == "where_negative":
        arrays["color_where"] = np.array([-1], np.int32)
    elif edit == "poisoned_over_k":
        arrays["color_poisoned"] = np.full((2, 3), 3, np.uint8)
    else:
        arrays["color_first"] = arrays["color_first"][..., :1]
        arrays["color_steps"] = arrays["color_steps"][:, :1]
    np.savez(tmp_path / "a.npz", **arrays)
    monkeypatch.setattr(shipped, "FOLDER", tmp_path)
    (tmp_path / shipped.INDEX).write_text(json.dumps({"k1": "a.npz"}))
    shipped._index.cache_clear()
    try:
        assert shipped.read("k1", ("color",), (2, 3), 2) is None
    finally:
        shipped._index.cache_clear()


def jittered_cases() -> list[tuple[Case, Renderer, int]]:
    """tools/make_distributions.py's cases: those the shipped data is made for."""
    sys.path.insert(0, str(TOOLS))
    try:
        from make_distributions import cases
    finally:
        sys.path.remove(str(TOOLS))
    return cases()


def test_every_jittered_case_of_a_bundled_check_and_report_is_shipped_and_nothing_else():
    """A bundled scene, its case matrix or a reference's identity changed without
    tools/make_distributions.py run again: the first check or report would render what it
    should read. 66 jittered cases each: the tracer's for a check, Mitsuba's for the report."""
    found = jittered_cases()
    keys = {shipped.shipped_key(reference, c.scene.path, c.request, k, REFERENCE_SEED)
            for c, reference, k in found}
    index = json.loads((shipped.FOLDER / shipped.INDEX).read_text())
    assert sorted(r.name for _, r, _ in found) == ["mitsuba"] * 66 + ["tracer"] * 66
    assert set(index) == keys
    assert sorted(index.values()) == sorted(p.name for p in shipped.FOLDER.glob("*.npz"))


@pytest.mark.parametrize("which", ["smallest", "all"])
def test_the_shipped_distributions_are_those_the_references_render_now(which, full_run,
                                                                       tmp_path, monkeypatch):
    """Byte for byte, and what reference_distribution returns with an empty cache (in the
    quick run the 9x7 and 37x20 cases and one course scene's at 128x128, of each reference;
    every one in the full run). Mitsuba's on a CPU of another vector instruction set than the
    data's (shipped.py): at most OTHER_ISA_SHARE of a kind's bytes differ."""
    if which == "all" and not full_run:
        pytest.skip("every shipped distribution rendered again (minutes): run with --full")
    monkeypatch.setenv("RAYCHECK_CACHE", str(tmp_path))  # an empty raycheck cache
    other_isa = json.loads((shipped.FOLDER / shipped.MADE_ON).read_text())["vector isa"] \
        != vector_isa()
    found = jittered_cases()
    if which == "smallest":
        found = [(c, r, k) for c, r, k in found if c.request.width * c.request.height < 1000
                 or c.id == "spheres_mirror/jitter"]
        assert len(found) == 10
    for case, reference, k in found:
        fresh = render_realisations(reference, case.scene.path, case.request, k)
        read = reference_distribution(reference, case.scene.path, case.request, k)
        assert read.cached and read.seconds == 0.0, (reference.name, case.id)
        bounded = reference.name == "mitsuba" and other_isa
        for kind, d in fresh.items():
            where = (reference.name, case.id, kind)
            differ = np.count_nonzero(read.kinds[kind].bytes != d.bytes)
            assert differ <= (OTHER_ISA_SHARE * d.bytes.size if bounded else 0), where + (differ,)
            assert np.array_equal(read.kinds[kind].poisoned, d.poisoned), where
            assert read.kinds[kind].poisoned.dtype == d.poisoned.dtype


@pytest.mark.parametrize("flags, isa", [("fpu sse sse2 avx avx2 fma avx512f avx512vl", "avx512"),
                                        ("fpu sse sse2 avx fma avx2", "avx2"),
                                        ("fpu sse sse2 avx", "avx"), ("fpu sse sse2", "sse")])
def test_the_vector_isa_is_the_widest_of_the_cpus_flags(flags, isa, tmp_path):
    info = tmp_path / "cpuinfo"
    info.write_text(f"processor\t: 0\nmodel name\t: Test CPU\nflags\t\t: {flags}\n\n"
                    f"processor\t: 1\nflags\t\t: {flags}\n")
    assert vector_isa(info) == isa
    assert vector_isa(tmp_path / "none") not in ("avx512", "avx2", "avx", "sse")
