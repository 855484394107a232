"""OBJ meshes as the course reads them (spec §3): positions and triangles only, normals rebuilt."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from .errors import SceneError, quote
from .lexer import FLOAT_RE, INT_RE, MAX_INT_DIGITS, SPACE_RE
from .limits import (
    MAX_OBJ_BYTES,
    MAX_OBJ_VERTICES,
    MAX_TRIANGLES,
    PARSE_BYTES_PER_FACE,
    PARSE_BYTES_PER_VERTEX,
    Budget,
    BudgetError,
    check_file_size,
)

F32 = np.float32


def _index(token: str, path: Path, lineno: int) -> int:
    head = token.split("/", 1)[0]
    if not INT_RE.fullmatch(head):
        raise SceneError(path, lineno, f"expected a vertex index in 'f' line, found {quote(token)}")
    if len(head.lstrip("+-").lstrip("0")) > MAX_INT_DIGITS:
        raise SceneError(path, lineno, "expected a vertex index of at most "
                         f"{MAX_INT_DIGITS} digits in 'f' line, found {quote(token)}")
    return int(head)


def parse_obj(text: str, path: Path) -> tuple[np.ndarray, np.ndarray]:
    """Vertices (V,3) float32 and 0-based faces (F,3) int64 from OBJ text.

    Lines are counted by '\n' and fields split at C whitespace, as in the scene lexer. Numbers
    too large for float32 become ±inf, silently (C's strtof)."""
    verts: list[tuple[float, float, float]] = []
    faces: list[tuple[int, int, int]] = []
    face_lines: list[int] = []
    for lineno, line in enumerate(text.split("\n"), start=1):
        if len(line) < 3 or line.startswith("#"):
            continue
        parts = [p for p in SPACE_RE.split(line) if p]
        if not parts:
            continue
        tag = parts[0]
        if tag == "v":
            if len(parts) < 4 or not all(FLOAT_RE.fullmatch(p) for p in parts[1:4]):
                raise SceneError(path, lineno, "expected 'v x y z' with three numbers")
            verts.append((float(parts[1]), float(parts[2]), float(parts[3])))
            if len(verts) > MAX_OBJ_VERTICES:
                raise SceneError(path, lineno, f"more than {MAX_OBJ_VERTICES} vertices")
        elif tag == "f":
            if len(parts) < 4:
                raise SceneError(path, lineno, "expected 'f a b c' with three vertex indices")
            faces.append(tuple(_index(p, path, lineno) for p in parts[1:4]))  # type: ignore[arg-type]
            face_lines.append(lineno)
            if len(faces) > MAX_TRIANGLES:
                raise SceneError(path, lineno, f"more than {MAX_TRIANGLES} faces")
    with np.errstate(over="ignore"):
        v = np.array(verts, dtype=F32).reshape(-1, 3)
    f = np.array(faces, dtype=np.int64).reshape(-1, 3)
    bad = np.nonzero(((f < 1) | (f > len(v))).any(axis=1))[0]
    if len(bad):
        i = int(bad[0])
        raise SceneError(
            path, face_lines[i],
            f"face index out of range 1..{len(v)}: {' '.join(str(x) for x in f[i])}",
        )
    return v, f - 1


def face_normals(v: np.ndarray, f: np.ndarray) -> np.ndarray:
    """Unit normal normalize(cross(vb-va, vc-va)) of every face, float32."""
    a, b, c = v[f[:, 0]], v[f[:, 1]], v[f[:, 2]]
    with np.errstate(all="ignore"):  # inf/NaN vertices give NaN normals, as in float C code
        n = np.cross(b - a, c - a).astype(F32)
        return n / np.sqrt((n[:, 0] * n[:, 0] + n[:, 1] * n[:, 1]) + n[:, 2] * n[:, 2])[:, None]


def vertex_normals(v: np.ndarray, f: np.ndarray) -> np.ndarray:
    """The course's averaging rule: each face adds its unit normal to its three vertices (in
    file order), then every vertex sum is normalized."""
    fn = face_normals(v, f)
    acc = np.zeros_like(v, dtype=F32)
    # np.add.at is unbuffered and applies updates in order: face by face, corners a, b, c, so
    # each vertex sum is rounded exactly as in the course's loop.
    with np.errstate(all="ignore"):
        np.add.at(acc, f.reshape(-1), np.repeat(fn, 3, axis=0))
        norm = np.sqrt((acc[:, 0] * acc[:, 0] + acc[:, 1] * acc[:, 1]) + acc[:, 2] * acc[:, 2])
        return (acc / norm[:, None]).astype(F32)


_SPACES = (b" ", b"\t", b"\v", b"\f", b"\r")


def _count_lines(data: bytes, tag: bytes) -> int:
    """Lines starting with `tag` and a C space: a count at C speed, without a list."""
    return sum(data.count(b"\n" + tag + c) + data.startswith(tag + c) for c in _SPACES)


def check_obj_size(data: bytes, path: Path, ref_path: Path, ref_line: int,
                   budget: Budget) -> None:
    """Refuses a mesh by its counts of 'f' and 'v' lines, before the parse that would take
    minutes and gigabytes for it."""
    faces, vertices = _count_lines(data, b"f"), _count_lines(data, b"v")
    if faces > MAX_TRIANGLES:
        raise SceneError(ref_path, ref_line, f"OBJ file {path} has {faces} faces, over the "
                         f"limit of {MAX_TRIANGLES}")
    try:
        budget.check_memory(faces * PARSE_BYTES_PER_FACE + vertices * PARSE_BYTES_PER_VERTEX,
                            f"OBJ file {path} ({faces} faces)")
    except BudgetError as e:
        raise SceneError(ref_path, ref_line, str(e)) from None


def load_obj(path: Path, ref_path: Path, ref_line: int, budget: Budget = Budget()
             ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Vertices, faces and recomputed vertex normals of the OBJ file at path."""
    if not path.is_file():
        raise SceneError(ref_path, ref_line, f"OBJ file not found: {path}")
    check_file_size(path, MAX_OBJ_BYTES, ref_path, ref_line)
    try:
        data = path.read_bytes()
    except OSError as e:
        raise SceneError(ref_path, ref_line, f"cannot read OBJ file {path}: {e.strerror}") from None
    check_obj_size(data, path, ref_path, ref_line, budget)
    v, f = parse_obj(data.decode("utf-8", errors="replace"), path)
    if len(f) == 0:
        raise SceneError(path, None, "OBJ file has no faces")
    return v, f, vertex_normals(v, f)
