"""The files a scene reads besides itself (OBJ meshes, cube-map faces), a comment-free copy of
its text for course programs (the course format has no comments), and a digest of all of it
for caches and result keys."""
from __future__ import annotations

import hashlib
import os
import re
from pathlib import Path

from .model import CubeMap, Group, Mesh, Scene, SceneObject, Transform

_COMMENT_RE = re.compile(r"#[^\n]*")


def asset_files(scene: Scene) -> list[Path]:
    """Every mesh and cube-map face file the scene reads, each once, in file order."""
    files: list[Path] = []
    cube = scene.background.cube_map
    if cube is not None:
        files += [Path(cube.folder) / f"{name}.png" for name in CubeMap.FACE_NAMES]
    stack: list[SceneObject] = [scene.root]
    while stack:
        obj = stack.pop()
        if isinstance(obj, Group):
            stack.extend(reversed(obj.objects))
        elif isinstance(obj, Transform):
            stack.append(obj.child)
        elif isinstance(obj, Mesh):
            files.append(Path(obj.path))
    return list(dict.fromkeys(files))


def file_stats(scene_path: Path, scene: Scene) -> list[tuple[Path, int, int]]:
    """(path, modification time in ns, size) of the scene file and each asset it reads: what
    a process can keep work done on a parse by (equal stats: the same files). OSError where
    one has gone."""
    return _stats([Path(scene_path), *asset_files(scene)])


def files_unchanged(stats: list[tuple[Path, int, int]]) -> bool:
    """Whether the files of file_stats() still have those stats (one gone: no)."""
    try:
        return _stats([p for p, _, _ in stats]) == stats
    except OSError:
        return False


def _stats(paths: list[Path]) -> list[tuple[Path, int, int]]:
    return [(p, st.st_mtime_ns, st.st_size) for p in paths for st in [p.stat()]]


def without_comments(text: str) -> str:
    """The scene text with each `#` comment removed; lines stay where they were, so a course
    program's messages name the same line numbers."""
    return _COMMENT_RE.sub("", text)


def scene_digest(scene_path: Path, scene: Scene) -> str:
    """sha256 over the scene file and every asset it reads (names relative to the scene's
    folder, and contents): equal digests render equal images."""
    h = hashlib.sha256()
    base = Path(scene_path).resolve().parent
    for path in [Path(scene_path), *asset_files(scene)]:
        name = os.path.relpath(Path(path).resolve(), base)
        h.update(name.encode() + b"\0")
        h.update(Path(path).read_bytes())
        h.update(b"\0")
    return h.hexdigest()
