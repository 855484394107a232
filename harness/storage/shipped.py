"""The bundled scenes' reference distributions, made once and shipped as data: a new user's
first check or report of the bundled scenes renders none of the jittered cases' realisations
(64 renders of a 16-sample image each, nine times that with -filter: most of a cold check's or
report's work).

scenes/distributions/ holds one file per jittered case of `raycheck check` on the bundled
scenes at their default sizes (the tracer's realisations) and of `raycheck report` (Mitsuba's,
mitsuba-*.npz), written by tools/make_distributions.py, and index.json, which
maps each file's key to its name. The key (shipped_key) names everything the realisations
depend on except the engines' source: the scene's and its assets' bytes, the request but its
seed, K, the first seed and the reference's identity (name, versions, options). The engines'
source is left out on purpose, so that a change to the tracer that renders the same bytes
keeps the data; a change that renders other bytes is caught by the test that renders every
shipped distribution afresh and compares it byte for byte (tests/harness/test_shipped.py,
--full, as CI runs it), and the data is made again with the tool.

Mitsuba's renders depend on the CPU's vector instruction set (provenance.vector_isa): on another
one, a few samples in millions that graze an edge hit otherwise and a depth's last bit moves, so
a few bytes of a distribution in a million differ (none of the tracer's). made_on.json names the
instruction set the data was made on; elsewhere the test bounds Mitsuba's differences instead of
asking for every byte. A check judging against the data there sees those few values as part
of the realisations' spread (whether one ever moves a verdict is not measured).

A file is the realisations without loss, as few bytes as that takes: per kind, the first
realisation whole, the pixels where any realisation differs from it, with all K values of
those pixels (a jittered image varies where an edge, a shadow's or a highlight's, crosses a
pixel: 12% of a bundled scene's pixels at the median kind, 0-72% over all), and per pixel the
count of realisations decided by an inf/NaN/missed sample.
"""
from __future__ import annotations

import hashlib
import json
import lzma
import zipfile
from functools import lru_cache
from pathlib import Path

import numpy as np
from numpy.lib.npyio import NpzFile

from raycheck.tracer.scene.request import RenderRequest, request_fields

from ..catalog import SCENES
from ..renderers import Renderer
from .results import content_digest

FOLDER = SCENES / "distributions"
INDEX = "index.json"
MADE_ON = "made_on.json"  # {"vector isa": ...} of the machine that made the data


def shipped_key(reference: Renderer, scene: Path, request: RenderRequest, k: int,
                first_seed: int) -> str:
    """What a distribution depends on, but the engines' source (the module's docstring)."""
    fields = {n: v for n, v in request_fields(request).items() if n != "seed"}
    key = {"scene": content_digest(scene), "request": fields, "realisations": k,
           "first_seed": first_seed, "reference": reference.identity()}
    return hashlib.sha256(json.dumps(key, sort_keys=True, default=str).encode()).hexdigest()


def encode(bytes_: np.ndarray, poisoned: np.ndarray) -> dict[str, np.ndarray]:
    """One kind's realisations (K, h, w, C) uint8 and poisoned counts (h, w) as the arrays of
    a shipped file: first (h, w, C); where (n,), the flat indices of the pixels that vary;
    steps (n, C, K), their values less the first realisation's, modulo 256 (a pixel's K values
    side by side, as small numbers, compress best: a fifth fewer bytes than the values);
    poisoned (h, w) uint8."""
    k, h, w, c = bytes_.shape
    flat = bytes_.reshape(k, h * w, c)
    where = np.flatnonzero((flat != flat[:1]).any(axis=(0, 2))).astype(np.int32)
    varying = flat[:, where, :].transpose(1, 2, 0)
    return {"first": bytes_[0], "where": where,
            "steps": np.ascontiguousarray(varying - varying[..., :1]),
            "poisoned": poisoned.astype(np.uint8)}


def decode(first: np.ndarray, where: np.ndarray, steps: np.ndarray, k: int) -> np.ndarray:
    """encode's arrays back into the realisations (K, h, w, C) uint8."""
    h, w, c = first.shape
    flat = np.broadcast_to(first.reshape(1, h * w, c), (k, h * w, c)).copy()
    flat[:, where, :] = (steps + first.reshape(h * w, c)[where][..., None]).transpose(2, 0, 1)
    return flat.reshape(k, h, w, c)


def write(path: Path, kinds: dict[str, tuple[np.ndarray, np.ndarray]], key: str) -> None:
    """A shipped file: each kind's realisations and poisoned counts, and the key."""
    arrays = {"key": np.array(key)}
    for kind, (bytes_, poisoned) in kinds.items():
        arrays |= {f"{kind}_{name}": a for name, a in encode(bytes_, poisoned).items()}
    with zipfile.ZipFile(path, "w", zipfile.ZIP_LZMA) as z:
        for name, value in arrays.items():
            with z.open(f"{name}.npy", "w") as member:
                np.lib.format.write_array(member, value, allow_pickle=False)


@lru_cache(maxsize=1)
def _index() -> dict[str, str]:
    try:
        data = json.loads((FOLDER / INDEX).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return {}
    return data if isinstance(data, dict) else {}


def read(key: str, kinds: tuple[str, ...], size: tuple[int, int],
         k: int) -> dict[str, tuple[np.ndarray, np.ndarray]] | None:
    """The realisations (K, h, w, C) uint8 and poisoned counts (h, w) of each kind for a key,
    or None where none is shipped, or the file does not hold them whole at this size."""
    name = _index().get(key)
    if not isinstance(name, str):
        return None
    try:
        with np.load(FOLDER / name, allow_pickle=False) as data:
            if str(data["key"]) != key:
                return None
            found = {kind: _kind(data, kind, size, k) for kind in kinds}
    # a damaged or edited file (or a Python without lzma) is rendered instead, as a damaged
    # cache entry is: NotImplementedError is zipfile's for a member's unknown compression
    except (OSError, KeyError, ValueError, EOFError, IndexError, zipfile.BadZipFile,
            lzma.LZMAError, NotImplementedError, RuntimeError):
        return None
    return found


def _kind(data: NpzFile, kind: str, size: tuple[int, int],
          k: int) -> tuple[np.ndarray, np.ndarray]:
    """One kind's arrays of an open file, checked as _fits checks a cache entry (ValueError)."""
    first, where, steps, poisoned = (data[f"{kind}_{p}"] for p in
                                     ("first", "where", "steps", "poisoned"))
    channels = 1 if kind == "depth" else 3
    h, w = size
    if first.shape != (h, w, channels) or first.dtype != np.uint8 or \
            steps.shape != (len(where), channels, k) or steps.dtype != np.uint8 or \
            where.dtype != np.int32 or (len(where) and (where.min() < 0 or where.max() >= h * w)) \
            or poisoned.shape != size or poisoned.dtype != np.uint8 or poisoned.max() > k:
        raise ValueError(f"{kind}: not {k} realisations at {w}x{h}")
    return decode(first, where, steps, k), poisoned.astype(np.int64)
