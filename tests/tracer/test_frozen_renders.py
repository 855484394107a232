"""A Renderer traces its launches once and replays them after (dr.freeze): a replayed render
gives the traced render's images bit for bit, whatever the features and launch splits; a
change of what the kernel is made from traces again; and garbage collection during the
recording does not abort the process."""
from __future__ import annotations

import subprocess
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from raycheck.tracer import render as render_module
from raycheck.tracer.options import RenderOptions
from raycheck.tracer.render import Renderer
from raycheck.tracer.scene import load_scene

REPO = Path(__file__).resolve().parents[2]
KINDS = ("color", "normals", "depth")


def images(r: Renderer) -> list[np.ndarray]:
    result = r.render()
    return [getattr(result, k) for k in r.opts.kinds] + [result.aux[k] for k in sorted(result.aux)]


@pytest.mark.parametrize("scene, options", [
    ("course/arch", dict(bounces=3, shadows=True)),
    ("course/cubemap_mesh", dict(bounces=2, shadows=True, filter=True)),
    ("course/smooth_mesh", dict(jitter=True, samples=5, shadows=True)),
    ("course/spheres_mirror", dict(bounces=4, aux=("object", "mirror_depth", "shadow"))),
])
def test_replayed_renders_equal_the_traced_one(monkeypatch, scene: str, options: dict):
    # a launch of at most 16 x 32 ray casts: several launches, the jittered samples in chunks
    monkeypatch.setattr(render_module, "LAUNCH_WORK", 16 * 32)
    opts = RenderOptions(16, 12, kinds=KINDS, depth_min=3, depth_max=12, **options)
    r = Renderer(load_scene(REPO / "scenes" / f"{scene}.txt"), opts)
    assert len(r.launches()) > 1
    traced = images(r)
    for _ in range(2):
        again = images(r)
        assert len(again) == len(traced)
        for a, b in zip(again, traced):
            assert a.tobytes() == b.tobytes()
    assert r._frozen.n_recordings == len(r.launches())  # one a launch: then replays


class Shifted(Renderer):
    """Samples shifted by a plain attribute, read as a run-time value."""

    shift = 0.0

    def _sample(self, px, py, tile=None) -> dict:
        return super()._sample(px + self._opaque(self.T.Float, self.shift), py, tile)


def test_a_changed_plain_attribute_traces_again():
    opts = RenderOptions(16, 12, kinds=("depth",), depth_min=3, depth_max=12)
    r = Shifted(load_scene(REPO / "scenes" / "course" / "ellipsoid.txt"), opts)
    first = r.render().depth
    r.shift = 0.5
    shifted = r.render().depth
    assert not np.array_equal(first, shifted)
    fresh = Shifted(load_scene(REPO / "scenes" / "course" / "ellipsoid.txt"), opts)
    fresh.shift = 0.5
    assert np.array_equal(shifted, fresh.render().depth)
    r.shift = 0.0
    assert np.array_equal(first, r.render().depth)


def test_a_new_seed_replays_and_other_new_options_trace_again():
    """The harness reseeds a renderer between jittered renders by replacing its options: the
    seed is a run-time argument of the launch, any other option is part of what it is made
    from."""
    scene = load_scene(REPO / "scenes" / "course" / "ellipsoid.txt")
    opts = RenderOptions(16, 12, jitter=True, samples=3, seed=1, shadows=True)
    r = Renderer(scene, opts)
    first = r.render().color
    for seed in (2, 3, 4):
        r.opts = replace(opts, seed=seed)
        again = r.render().color
        assert not np.array_equal(first, again)
        assert np.array_equal(again, Renderer(scene, replace(opts, seed=seed)).render().color)
    assert r._frozen.n_recordings == 1  # every reseeded render was a replay
    r.opts = replace(opts, depth_min=1.0)  # not read by this color render: the same launch,
    assert np.array_equal(r.render().color, first)  # but another key: traced again
    assert r._frozen.n_recordings == 2


class Failing(Renderer):
    def _sample(self, px, py, tile=None) -> dict:
        raise ValueError("no such image")


def test_an_error_while_a_launch_is_traced_is_raised_as_itself():
    r = Failing(load_scene(REPO / "scenes" / "course" / "ellipsoid.txt"), RenderOptions(8, 8))
    with pytest.raises(ValueError, match="no such image"):
        r.render()


def test_the_collector_stays_paused_while_any_thread_records():
    """Two threads' launches overlap: the first to finish must not restart the collector
    under the other's recording."""
    import gc
    import threading

    from raycheck.tracer.kernel.frozen import gc_paused

    inside, release = threading.Event(), threading.Event()

    def other():
        with gc_paused():
            inside.set()
            release.wait(10)

    thread = threading.Thread(target=other)
    assert gc.isenabled()
    with gc_paused():
        thread.start()
        assert inside.wait(10)
    assert not gc.isenabled()  # the other thread is still inside
    release.set()
    thread.join(10)
    assert gc.isenabled()


def test_garbage_collection_while_recording_does_not_abort():
    """A process that has rendered many scenes leaves renderers for the cyclic collector; one
    collected while a launch is recorded aborted Dr.Jit 1.5 ("enqueue_host_func(): this
    function cannot be recorded", in 9 pytest workers of one suite run) before
    frozen.gc_paused. This loop aborted in each of its runs without it."""
    code = """
from pathlib import Path
from raycheck.tracer.options import RenderOptions
from raycheck.tracer.render import Renderer
from raycheck.tracer.scene import load_scene

scenes = [p for d in ("course", "features") for p in sorted(Path("scenes", d).glob("*.txt"))]
for round in range(3):
    for path in scenes:
        r = Renderer(load_scene(path), RenderOptions(16, 12, bounces=2, shadows=True))
        r.render()
        r.render()
        cycle = [r]
        cycle.append(cycle)  # garbage for the collector, as long-lived processes leave
        del r, cycle
print("done")
"""
    proc = subprocess.run([sys.executable, "-c", code], cwd=REPO, capture_output=True,
                          text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert proc.stdout.strip() == "done"
