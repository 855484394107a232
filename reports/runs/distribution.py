"""The reference's sampling distribution of a jittered request: K independent realisations
(seeds REFERENCE_SEED + 0..K-1) of the same 16-sample image, kept per kind as their 8-bit values
(the course's quantisation, metrics.bytes8: clamping and rounding are part of the distribution)
and the share of realisations in which each pixel is decided by an inf/NaN/missed sample
(verdict.poisoned).

Cached on disk, one .npz per key ($RAYCHECK_CACHE, else ~/.cache/raycheck/), keyed by the
scene's and its assets' content (scene_digest), every request field but the seed, K, the
reference's identity and the raycheck version: a second check of the same case renders nothing.
"""
from __future__ import annotations

import hashlib
import json
import os
import tempfile
import time
from dataclasses import dataclass, replace
from importlib.metadata import version
from pathlib import Path

import numpy as np

from raycheck.tracer.scene import load_scene
from raycheck.tracer.scene.assets import scene_digest
from raycheck.tracer.scene.request import RenderRequest, request_fields

from ..judge import metrics
from ..judge.verdict import poisoned
from ..renderers import Renderer

DEFAULT_REALISATIONS = 64
# Realisation i renders with seed REFERENCE_SEED + i: far from the small seeds candidates use
# (0 by default, the benchmark's 0..N), and below 2^32 so Mitsuba's 32-bit sampler seeds
# (seed * 1000003 mod 2^32, a bijection) stay distinct from theirs too.
REFERENCE_SEED = 0x9E3779B9


@dataclass
class Distribution:
    """One kind's realisations: bytes (K, h, w, C) uint8 (C = 1 for depth), poisoned (h, w)."""

    bytes: np.ndarray
    poisoned: np.ndarray

    @property
    def mean(self) -> np.ndarray:
        """The mean 8-bit value as float image values (h, w, 3) or (h, w): (mu + 0.5) / 255,
        which the course's truncation shows as the rounded mean."""
        mu = (self.bytes.mean(axis=0) + 0.5) / 255.0
        return mu[..., 0] if mu.shape[-1] == 1 else mu


@dataclass
class Distributions:
    kinds: dict[str, Distribution]
    seconds: float  # rendering time of the K realisations (0 when all came from the cache)
    cached: bool


def cache_folder() -> Path:
    return Path(os.environ.get("RAYCHECK_CACHE") or Path.home() / ".cache" / "raycheck")


def cache_key(reference: Renderer, scene: Path, request: RenderRequest, k: int) -> str:
    fields = {n: v for n, v in request_fields(request).items() if n != "seed"}
    key = {"scene": scene_digest(scene, load_scene(scene)), "request": fields,
           "realisations": k, "first_seed": REFERENCE_SEED, "reference": reference.identity(),
           "raycheck": version("raycheck")}
    return hashlib.sha256(json.dumps(key, sort_keys=True, default=str).encode()).hexdigest()


def as_bytes(image: np.ndarray) -> np.ndarray:
    """The 8-bit values of a float or PNG image, (h, w, C)."""
    from ..judge.verdict import as_values

    b = metrics.bytes8(as_values(image)).astype(np.uint8)
    return b[..., None] if b.ndim == 2 else b


def _realisations(reference: Renderer, scene: Path, request: RenderRequest, k: int):
    if reference.caps.reseed:
        session = reference.open(scene, replace(request, seed=REFERENCE_SEED))
        try:
            for i in range(k):
                session.reseed(REFERENCE_SEED + i)
                yield session.render().images
        finally:
            session.close()
        return
    for i in range(k):
        session = reference.open(scene, replace(request, seed=REFERENCE_SEED + i))
        try:
            yield session.render().images
        finally:
            session.close()


def render_realisations(reference: Renderer, scene: Path, request: RenderRequest,
                        k: int) -> dict[str, Distribution]:
    """Renders the K realisations: in one session where the renderer can reseed one (the
    built-in renderers: the scene is loaded and its kernel compiled once), else one session
    per seed."""
    stacks: dict[str, list[np.ndarray]] = {kind: [] for kind in request.kinds}
    bad: dict[str, np.ndarray] = {}
    for images in _realisations(reference, scene, request, k):
        for kind in request.kinds:
            stacks[kind].append(as_bytes(images[kind]))
            bad[kind] = bad.get(kind, 0) + poisoned(images[kind])
    return {kind: Distribution(np.stack(stacks[kind]), (bad[kind] / k).astype(np.float32))
            for kind in request.kinds}


def reference_distribution(reference: Renderer, scene: Path, request: RenderRequest,
                           k: int = DEFAULT_REALISATIONS, cache: bool = True) -> Distributions:
    """The distribution of each requested kind, from the cache or rendered (then cached)."""
    path = cache_folder() / f"{cache_key(reference, scene, request, k)}.npz" if cache else None
    if path is not None and path.is_file():
        try:
            with np.load(path) as data:
                kinds = {kind: Distribution(data[f"{kind}_bytes"], data[f"{kind}_poisoned"])
                         for kind in request.kinds}
            return Distributions(kinds, 0.0, True)
        except (OSError, KeyError, ValueError):
            pass  # a damaged entry is rendered again and replaced
    start = time.perf_counter()
    kinds = render_realisations(reference, scene, request, k)
    seconds = time.perf_counter() - start
    if path is not None:
        _write_atomically(path, {f"{kind}_{part}": getattr(d, part) for kind, d in kinds.items()
                                 for part in ("bytes", "poisoned")})
    return Distributions(kinds, seconds, False)


def _write_atomically(path: Path, arrays: dict[str, np.ndarray]) -> None:
    """Writes beside and renames: a concurrent reader sees the old entry or the new, whole. A
    cache that cannot be written only costs the next check the rendering."""
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=path.parent, suffix=".npz.tmp")
        try:
            with os.fdopen(fd, "wb") as f:
                np.savez_compressed(f, **arrays)
            os.replace(tmp, path)
        except BaseException:
            os.unlink(tmp)
            raise
    except OSError:
        pass
