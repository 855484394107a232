"""The two renderers of this project, in process: the tracer (tracer.render) and the Mitsuba
reference (mitsuba_ref.render). Both return float images and honour seeds and sample counts;
a session keeps the loaded scene and its compiled kernels for warm re-runs, and the tracer
keeps a scene's parse and intersector across the sessions (flag sets) of a process."""
from __future__ import annotations

import threading
import time
from collections import OrderedDict
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import ClassVar

from raycheck.tracer.scene import SceneError, load_scene
from raycheck.tracer.scene.assets import file_stats, files_unchanged
from raycheck.tracer.scene.limits import Budget, scene_request_problem
from raycheck.tracer.scene.request import RenderRequest, request_fields

from ..versions import package_version
from .base import Capabilities, Images, RenderError

CAPS = Capabilities(float_images=True, seedable=True, warm_reruns=True, reseed=True)


class _Session:
    def __init__(self, renderer, kinds: tuple[str, ...], close=None) -> None:
        self._renderer = renderer
        self._kinds = kinds
        self._close = close

    def render(self) -> Images:
        start = time.perf_counter()
        result = self._renderer.render()
        images = {k: getattr(result, k) for k in self._kinds}
        return Images(images, time.perf_counter() - start)

    def reseed(self, seed: int) -> None:
        """The next render() draws the jitter samples of `seed`: both renderers take the seed
        as a runtime value, so nothing is loaded or compiled again."""
        self._renderer.opts = replace(self._renderer.opts, seed=seed)

    def close(self) -> None:
        if self._close:
            self._close()
        self._renderer = None


def _scene(path: Path, request: RenderRequest, budget: Budget):
    """The scene, within the limits both renderers share (scene.limits), or RenderError."""
    try:
        scene = load_scene(path, budget)
    except SceneError as e:
        raise RenderError("bad_input", str(e)) from None
    _within_limits(scene, request, budget)
    return scene


def _within_limits(scene, request: RenderRequest, budget: Budget) -> None:
    problem = request.limit_problem() or scene_request_problem(scene, request, budget)
    if problem:
        raise RenderError("bad_input", problem)


@dataclass
class _Builtin:
    """What both in-process renderers hold: `options` are their option record's engine
    fields, and the versions that make their results reproducible."""

    name: str
    options: dict = field(default_factory=dict)
    budget: Budget = Budget()
    caps: Capabilities = CAPS
    engine_packages: ClassVar[tuple[str, ...]] = ()

    def identity(self) -> dict:
        return {"name": self.name, "raycheck": package_version("raycheck"),
                **{p: package_version(p) for p in self.engine_packages}, **self.options}


class _Prepared:
    """The scenes a process rendered last, parsed, each with its intersectors (BVH, octrees,
    instances on the device) per backend, precision, accel and mode: the cases of one scene
    are its flag sets, and each would otherwise parse the scene and build them again (up to
    0.1 s a case for the course scenes with meshes, where a 128x128 render takes 0.01-0.05 s).
    An entry is used only while the scene file and its assets keep their size and
    modification time. Locked: a Dask worker may run cases in threads."""

    KEEP = 2  # scenes: a matrix's cases come scene by scene

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._entries: OrderedDict = OrderedDict()  # (path, budget) -> (stats, scene, {key: isect})

    def scene(self, path: Path, budget: Budget):
        """(the parsed scene, its intersectors by key), parsing it where none is kept. A parse
        is kept only where the scene file has the same stats before and after it (an asset
        rewritten while it is being parsed is not seen: content_digest shares that window)."""
        path = Path(path)  # parsed as given: relative asset paths and messages follow it
        key = (path.resolve(), budget)  # stat() follows links as resolve() does
        with self._lock:
            entry = self._entries.get(key)
            if entry is not None and files_unchanged(entry[0]):
                self._entries.move_to_end(key)
                return entry[1], entry[2]
        try:
            before = path.stat()
        except OSError:
            before = None  # the parse says what is wrong
        scene = load_scene(path, budget)
        try:
            stats = file_stats(path, scene)
        except OSError:
            return scene, {}
        if before is None or (before.st_mtime_ns, before.st_size) != stats[0][1:]:
            return scene, {}
        with self._lock:
            self._entries[key] = (stats, scene, {})
            while len(self._entries) > self.KEEP:
                self._entries.popitem(last=False)
            return scene, self._entries[key][2]


_prepared = _Prepared()


@dataclass
class TracerRenderer(_Builtin):
    """raycheck's tracer; options: mode, precision, backend."""

    name: str = "tracer"

    def open(self, scene: Path, request: RenderRequest) -> _Session:
        from raycheck.tracer.options import OptionError, RenderOptions
        from raycheck.tracer.render import Renderer
        from raycheck.tracer.render_limits import LimitError, check_render_limits

        try:
            opts = RenderOptions(**request_fields(request), **self.options)
            check_render_limits(opts)
        except (OptionError, LimitError) as e:
            raise RenderError("bad_input", str(e)) from None
        try:
            model, intersectors = _prepared.scene(scene, self.budget)
        except SceneError as e:
            raise RenderError("bad_input", str(e)) from None
        _within_limits(model, request, self.budget)
        key = (opts.backend, opts.precision, opts.accel, opts.mode, opts.mistakes)
        renderer = Renderer(model, opts, intersectors.get(key))
        intersectors[key] = renderer.isect
        return _Session(renderer, request.kinds)


@dataclass
class MitsubaRenderer(_Builtin):
    """The Mitsuba 3 reference; options: variant, offsets."""

    name: str = "mitsuba"
    engine_packages: ClassVar[tuple[str, ...]] = ("mitsuba",)

    def open(self, scene: Path, request: RenderRequest) -> _Session:
        from raycheck.mitsuba_ref.render import OptionError, ReferenceOptions, ReferenceRenderer

        opts = ReferenceOptions(**request_fields(request), **self.options)
        try:
            opts.check()
        except OptionError as e:
            raise RenderError("bad_input", str(e)) from None
        r = ReferenceRenderer(_scene(scene, request, self.budget), opts)
        return _Session(r, request.kinds, r.close)


DEPTH_PROBE_SIZE = (64, 64)
DEPTH_PADDING = 0.05  # of the range, on each side: the nearest and farthest hits stay inside


def visible_depth_range(scene: Path, size: tuple[int, int] = DEPTH_PROBE_SIZE
                        ) -> tuple[float, float] | None:
    """A depth range for a scene that names none: the range of finite distances of the
    tracer's primary hits at `size`, padded by DEPTH_PADDING (not below 0), or None when no ray
    hits."""
    import numpy as np

    probe = RenderRequest(*size, kinds=("depth",), depth_min=0.0, depth_max=1.0)
    t = TracerRenderer().open(scene, probe).render().images["depth"]  # (t - 0) / 1 = t
    with np.errstate(invalid="ignore"):
        hits = t[np.isfinite(t) & (t < 1e30)]
    if not hits.size:
        return None
    lo, hi = float(hits.min()), float(hits.max())
    pad = DEPTH_PADDING * (hi - lo) if hi > lo else max(1.0, abs(lo) * DEPTH_PADDING)
    return float(np.float32(max(0.0, lo - pad))), float(np.float32(hi + pad))
