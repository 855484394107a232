"""The reference's sampling distribution of a jittered request: K independent realisations
(seeds REFERENCE_SEED + 0..K-1) of the same 16-sample image, kept per kind as their 8-bit values
(the course's quantisation, metrics.bytes8: clamping and rounding are part of the distribution)
and the share of realisations in which each pixel is decided by an inf/NaN/missed sample
(verdict.poisoned).

Cached on disk, one .npz per key (disk_cache.py), keyed by the scene's and its assets'
content (scene_digest), every request field but the seed, K, the reference's identity, the
raycheck version and the engines' source (disk_cache.engine_digest): a second check of the
same case renders nothing. What the statistical test derives from the realisations
(statistics.prepare, a tenth of a second a kind) is cached beside them, per test and channel
count.
"""
from __future__ import annotations

import hashlib
import json
import time
from dataclasses import dataclass, fields, replace
from pathlib import Path
from typing import Any

import numpy as np

from raycheck.tracer.scene.request import RenderRequest, request_fields

from ..judge import metrics
from ..judge.statistics import JitterTest, Reference, prepare
from ..judge.verdict import poisoned
from ..renderers import Renderer, Reseedable
from ..versions import package_version
from . import shipped
from .disk_cache import cache_folder, engine_digest, load_arrays, save_arrays
from .results import content_digest

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

    def prepared(self, channels: int, test: JitterTest, path: Path | None) -> Reference:
        """statistics.prepare of the realisations for a candidate of `channels` channels
        (a depth PNG's 3: the one channel replicated, as verdict.jitter_result does), read
        from or written to `path` (None: not cached)."""
        data = load_arrays(path) if path is not None else None
        names = [f.name for f in fields(Reference)]
        if data is not None and self._prepared_fits(data, names, channels):
            saved: dict[str, Any] = {n: data[n] if data[n].ndim else data[n].item()
                                     for n in names}
            return Reference(**saved)
        r = self.bytes
        if r.shape[-1] != channels:
            r = np.repeat(r, channels, axis=-1)
        ref = prepare(r, self.poisoned, test)
        if path is not None:
            save_arrays(path, {n: np.asarray(getattr(ref, n)) for n in names}, compress=False)
        return ref

    def _prepared_fits(self, data: dict, names: list[str], channels: int) -> bool:
        """Whether a cache entry holds a Reference of these realisations (a damaged or edited
        one is prepared again): the scalars as scalars, the images at their size."""
        if not all(n in data for n in names):
            return False
        size = self.bytes.shape[1:3]
        shapes = {"k": (), "limit": (), "lam": (), "mu": (*size, channels),
                  "scale": (*size, channels)}
        return all(data[n].shape == shapes.get(n, size) and data[n].dtype.kind in "fiub"
                   for n in names)


@dataclass
class Distributions:
    kinds: dict[str, Distribution]
    seconds: float  # rendering time of the K realisations (0 when all came from the cache)
    cached: bool
    key: str | None = None  # of the cache entry (None: not cached)

    def prepared(self, kind: str, channels: int, test: JitterTest) -> Reference:
        """The kind's realisations as the statistical test needs them, cached by test."""
        path = None
        if self.key is not None:
            sub = hashlib.sha256(f"{kind} {channels} {test.describe()}".encode()).hexdigest()
            path = cache_folder() / "prepared" / f"{self.key}-{sub[:16]}.npz"
        return self.kinds[kind].prepared(channels, test, path)


def cache_key(reference: Renderer, scene: Path, request: RenderRequest, k: int) -> str:
    fields = {n: v for n, v in request_fields(request).items() if n != "seed"}
    key = {"scene": content_digest(scene), "request": fields,
           "realisations": k, "first_seed": REFERENCE_SEED, "reference": reference.identity(),
           "raycheck": package_version("raycheck"), "engines": engine_digest()}
    return hashlib.sha256(json.dumps(key, sort_keys=True, default=str).encode()).hexdigest()


def as_bytes(image: np.ndarray) -> np.ndarray:
    """The 8-bit values of a float or PNG image, (h, w, C)."""
    from ..judge.verdict import as_values

    b = metrics.bytes8(as_values(image)).astype(np.uint8)
    return b[..., None] if b.ndim == 2 else b


def _realisations(reference: Renderer, scene: Path, request: RenderRequest, k: int):
    if reference.caps.reseed:
        session = reference.open(scene, replace(request, seed=REFERENCE_SEED))
        assert isinstance(session, Reseedable)  # what caps.reseed promises
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


def _fits(data: dict, kind: str, request: RenderRequest, k: int) -> bool:
    """Whether a cache entry holds kind's K realisations at the request's size (a damaged or
    edited entry is rendered again)."""
    b, p = data.get(f"{kind}_bytes"), data.get(f"{kind}_poisoned")
    size = (request.height, request.width)
    return (isinstance(b, np.ndarray) and isinstance(p, np.ndarray) and b.dtype == np.uint8
            and b.shape == (k, *size, 1 if kind == "depth" else 3) and p.shape == size)


def reference_distribution(reference: Renderer, scene: Path, request: RenderRequest,
                           k: int = DEFAULT_REALISATIONS, cache: bool = True,
                           use_shipped: bool = True) -> Distributions:
    """The distribution of each requested kind, from the cache, else from the data shipped for
    the bundled scenes (use_shipped, shipped.py), else rendered (then cached)."""
    key = cache_key(reference, scene, request, k) if cache else None
    path = cache_folder() / f"{key}.npz" if key is not None else None
    data = load_arrays(path) if path is not None else None
    if data is not None and all(_fits(data, kind, request, k) for kind in request.kinds):
        kinds = {kind: Distribution(data[f"{kind}_bytes"], data[f"{kind}_poisoned"])
                 for kind in request.kinds}
        return Distributions(kinds, 0.0, True, key)
    # the shipped data is not copied into the cache: read, it costs what a cache entry would
    found = shipped.read(shipped.shipped_key(reference, scene, request, k, REFERENCE_SEED),
                         request.kinds, (request.height, request.width), k) \
        if use_shipped else None
    if found is not None:
        kinds = {kind: Distribution(b, (bad / k).astype(np.float32))
                 for kind, (b, bad) in found.items()}
        return Distributions(kinds, 0.0, True, key)
    # a missing or damaged entry is rendered again and replaced
    start = time.perf_counter()
    kinds = render_realisations(reference, scene, request, k)
    seconds = time.perf_counter() - start
    if path is not None:
        save_arrays(path, {f"{kind}_{part}": getattr(d, part) for kind, d in kinds.items()
                           for part in ("bytes", "poisoned")})
    return Distributions(kinds, seconds, False, key)
