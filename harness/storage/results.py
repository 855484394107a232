"""Finished work kept on disk, keyed by content, so that a rerun redoes only what changed.

* ResultCache: one entry per case result (its JSON row and its PNG files), keyed by the
  candidate's and reference's identity (a program's sha256, raycheck's version for the built-in
  renderers), the scene's and its assets' content (scene_digest), the request and the
  tolerance. `--resume` reuses entries; a run without it starts the cache afresh.
* CachedRenderer: a renderer whose renders are kept as .npz by the same kind of key, so that
  grading a class renders the reference of each case once, not once per submission.

Both write each entry under a temporary name and rename it into place: an entry is there
whole or not at all, whatever kills the run (kill -9 included). The caches live beside the
output folder (`.DIR.cache/`), not in it: the output folder is built in a staging folder that
an interrupted run throws away, and finished results must outlive that.
"""
from __future__ import annotations

import hashlib
import json
import os
import shutil
import tempfile
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from raycheck.tracer.scene import load_scene
from raycheck.tracer.scene.assets import file_stats, files_unchanged, scene_digest
from raycheck.tracer.scene.request import RenderRequest

from ..records import CaseRecord, from_json, to_json
from ..renderers import (
    Capabilities,
    Images,
    Renderer,
    Reseedable,
    Session,
    fits_request,
)

FORMAT = 6  # bump when a cached row's layout changes: old entries then miss


def cache_folder(out: Path) -> Path:
    """Where the caches of output folder `out` live: `.OUT.cache` beside it."""
    out = Path(out).resolve()
    return out.parent / f".{out.name}.cache"


def content_key(*parts) -> str:
    """sha256 of the parts as canonical JSON (Paths and tuples as strings and lists)."""
    text = json.dumps([FORMAT, *parts], sort_keys=True, default=str)
    return hashlib.sha256(text.encode()).hexdigest()


_digests: dict[Path, tuple[list[tuple[Path, int, int]], str]] = {}


def content_digest(scene: Path) -> str:
    """scene_digest of a scene file: the scene's and its assets' bytes. Kept per file while
    neither it nor an asset it read changed (size and modification time), since every case
    key asks for it and parsing a mesh scene again costs milliseconds each time."""
    scene = Path(scene).resolve()
    known = _digests.get(scene)
    if known is not None and files_unchanged(known[0]):
        return known[1]
    model = load_scene(scene)
    digest = scene_digest(scene, model)
    try:
        _digests[scene] = (file_stats(scene, model), digest)
    except OSError:
        pass
    return digest


def request_key(renderer: Renderer, scene: Path, request: RenderRequest) -> list:
    """What a render depends on: the renderer, the scene's and assets' bytes, the request."""
    return [renderer.identity(), content_digest(scene), asdict(request)]


@dataclass
class CaseOutput:
    """What a worker sends back for one case: its record (with its picture files' names) and
    those files' bytes (8-bit PNGs: small, unlike the float images)."""

    row: CaseRecord
    files: dict[str, bytes]
    command: list[str]  # the course command line that reproduces the case (its page shows it)


def _rename_into_place(tmp: Path, final: Path) -> None:
    try:
        os.rename(tmp, final)
    except OSError:  # another worker stored the same entry first: keep theirs
        shutil.rmtree(tmp, ignore_errors=True) if tmp.is_dir() else tmp.unlink(missing_ok=True)


class ResultCache:
    def __init__(self, folder: Path) -> None:
        self.folder = Path(folder)

    def clear(self) -> None:
        shutil.rmtree(self.folder, ignore_errors=True)

    def load(self, key: str) -> CaseOutput | None:
        """The stored output, or None: none stored, or an entry whose checksum does not match
        (damaged, or edited by hand: its case runs again)."""
        entry = self.folder / key
        try:
            meta = json.loads((entry / "row.json").read_text(encoding="utf-8"))
            files = {p.name: p.read_bytes() for p in entry.iterdir() if p.name != "row.json"}
            output = CaseOutput(from_json(CaseRecord, meta["row"]), files, meta["command"])
            return output if meta["sha256"] == _checksum(output) else None
        except (OSError, ValueError, KeyError, TypeError):
            return None

    def store(self, key: str, output: CaseOutput) -> None:
        self.folder.mkdir(parents=True, exist_ok=True)
        tmp = Path(tempfile.mkdtemp(prefix=".tmp-", dir=self.folder))
        for name, data in output.files.items():
            (tmp / name).write_bytes(data)
        meta = {"row": to_json(output.row), "command": output.command,
                "sha256": _checksum(output)}
        (tmp / "row.json").write_text(json.dumps(meta), encoding="utf-8")
        _rename_into_place(tmp, self.folder / key)


def _checksum(output: CaseOutput) -> str:
    """sha256 of an output's row, command and files, as load reads them back."""
    digest = hashlib.sha256(json.dumps([to_json(output.row), output.command],
                                       sort_keys=True).encode())
    for name in sorted(output.files):
        digest.update(f"\0{name}\0{len(output.files[name])}\0".encode() + output.files[name])
    return digest.hexdigest()


@dataclass
class CachedRenderer:
    """`inner` with its renders kept in `folder`; a render found there is not redone. Only
    whole successful renders are kept (a failure is raised again next time)."""

    inner: Renderer
    folder: Path

    @property
    def name(self) -> str:
        return self.inner.name

    @property
    def caps(self) -> Capabilities:
        return self.inner.caps

    def identity(self) -> dict:
        return self.inner.identity()

    def open(self, scene: Path, request: RenderRequest) -> _CachedSession:
        return _CachedSession(self, Path(scene), request)


class _CachedSession:
    """Renders of one request through the cache. A reseeded session is drawing a jittered
    case's realisations, which the distribution keeps as a whole
    (distribution.reference_distribution): those go straight to the inner renderer's session,
    as K cached renders would be read never again."""

    def __init__(self, renderer: CachedRenderer, scene: Path, request: RenderRequest) -> None:
        self.renderer, self.scene, self.request = renderer, scene, request
        self._inner: Session | None = None  # opened by the first render the cache lacks
        self._reseeded = False

    def _session(self) -> Session:
        if self._inner is None:
            self._inner = self.renderer.inner.open(self.scene, self.request)
        return self._inner

    def reseed(self, seed: int) -> None:
        session = self._session()
        assert isinstance(session, Reseedable)  # only a reseeding renderer's sessions are
        session.reseed(seed)
        self._reseeded = True

    def render(self) -> Images:
        if self._reseeded:
            return self._session().render()
        r = self.renderer
        path = r.folder / f"{content_key(*request_key(r.inner, self.scene, self.request))}.npz"
        try:
            with np.load(path) as data:
                images = {k: data[k] for k in data.files if k != "_seconds"}
                seconds = float(data["_seconds"])
            if fits_request(images, self.request):
                return Images(images, seconds)
        except (OSError, ValueError, KeyError, TypeError):
            pass  # missing, damaged or not this request's: rendered again
        result = self._session().render()
        if not result.errors:
            tmp = None
            try:
                r.folder.mkdir(parents=True, exist_ok=True)
                fd, tmp = tempfile.mkstemp(prefix=".tmp-", suffix=".npz", dir=r.folder)
                with os.fdopen(fd, "wb") as f:
                    # numpy's stub reads **arrays as if one might be its allow_pickle
                    np.savez(f, _seconds=np.float64(result.seconds),
                             **result.images)  # type: ignore[arg-type]
                _rename_into_place(Path(tmp), path)
            except OSError:  # a worker on a node that cannot write there: it renders again
                if tmp:
                    Path(tmp).unlink(missing_ok=True)
        return result

    def close(self) -> None:
        if self._inner is not None:
            self._inner.close()
            self._inner = None
