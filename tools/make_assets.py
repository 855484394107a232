#!/usr/bin/env python3
"""Generate the procedural assets of the bundled scenes into scenes/assets/.

    .venv/bin/python tools/make_assets.py

Writes OBJ meshes (cube.obj, cube_flat.obj, sphere.obj, torus.obj) and a cube map folder
(sky/ with left/right/up/down/front/back.png). Everything is computed from fixed formulas, OBJ
numbers are written with fixed precision and PNGs carry no timestamp, so every run produces
byte-identical files and the generated files can be kept in the repository.

The meshes are written so the course's OBJ rules (spec §3) are exercised: the course recomputes
vertex normals by averaging face normals over SHARED vertices, so a mesh's smoothness is decided
by its vertex sharing, not by its `vn` lines (which the course ignores).
"""
from __future__ import annotations

import argparse
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from PIL import Image

ASSETS = Path(__file__).resolve().parent.parent / "scenes" / "assets"
DIGITS = 6  # fixed precision of OBJ coordinates: stable text, float32-exact enough
FACE_SIZE = 64  # cube-map faces are FACE_SIZE x FACE_SIZE 8-bit RGB

Vec3 = tuple[float, float, float]


# --------------------------------------------------------------------------------------------
# Meshes
# --------------------------------------------------------------------------------------------
@dataclass
class Mesh:
    """An indexed triangle mesh; faces are 0-based here and written 1-based."""

    vertices: list[Vec3] = field(default_factory=list)
    faces: list[tuple[int, int, int]] = field(default_factory=list)
    texcoords: list[tuple[float, float]] = field(default_factory=list)  # per vertex, optional
    normals: list[Vec3] = field(default_factory=list)  # per vertex, optional (course ignores)

    def add_vertex(self, p: Vec3) -> int:
        self.vertices.append(p)
        return len(self.vertices) - 1


def _num(x: float) -> str:
    # `+ 0.0` turns -0.0 into 0.0 so tiny negative rounding never prints as "-0.000000".
    return f"{round(x, DIGITS) + 0.0:.{DIGITS}f}"


def _check_outward(mesh: Mesh, center: Vec3 = (0.0, 0.0, 0.0)) -> None:
    """Every face must wind counter-clockwise seen from outside (cross(b-a, c-a) outward) and
    have non-zero area: a degenerate face has a NaN unit normal in the course's averaging rule,
    which would poison the normals of its vertices."""
    v = np.array(mesh.vertices, dtype=np.float64)
    f = np.array(mesh.faces, dtype=np.int64)
    a, b, c = v[f[:, 0]], v[f[:, 1]], v[f[:, 2]]
    n = np.cross(b - a, c - a)
    area = np.linalg.norm(n, axis=1)
    if (area < 1e-9).any():
        raise AssertionError("degenerate triangle in generated mesh")
    centroid = (a + b + c) / 3.0 - np.array(center)
    if ((n * centroid).sum(axis=1) <= 0).any():
        raise AssertionError("inward-wound triangle in generated mesh")


def obj_text(mesh: Mesh, header: list[str], uv_faces: bool = False) -> str:
    """OBJ text: header comments, v (and optional vt, vn) lines, then f lines.

    With uv_faces each face is written `f a/ta b/tb c/tc` (texcoord index = vertex index), the
    slash form the course accepts and ignores after the slash."""
    lines = [f"# {h}" if h else "#" for h in header]
    lines.append(f"# {len(mesh.vertices)} vertices, {len(mesh.faces)} triangles")
    lines.append("")
    lines += [f"v {_num(x)} {_num(y)} {_num(z)}" for x, y, z in mesh.vertices]
    if mesh.texcoords:
        lines.append("")
        lines += [f"vt {_num(s)} {_num(t)}" for s, t in mesh.texcoords]
    if mesh.normals:
        lines.append("")
        lines += [f"vn {_num(x)} {_num(y)} {_num(z)}" for x, y, z in mesh.normals]
    lines.append("")
    for a, b, c in mesh.faces:
        if uv_faces:
            lines.append(f"f {a + 1}/{a + 1} {b + 1}/{b + 1} {c + 1}/{c + 1}")
        else:
            lines.append(f"f {a + 1} {b + 1} {c + 1}")
    return "\n".join(lines) + "\n"


# The six faces of [-1,1]^3 as (outward axis, sign); corners are listed counter-clockwise
# seen from outside so the triangles (0,1,2), (0,2,3) face outward.
_CUBE_FACES: list[list[Vec3]] = [
    [(1, -1, -1), (1, 1, -1), (1, 1, 1), (1, -1, 1)],  # +x
    [(-1, -1, 1), (-1, 1, 1), (-1, 1, -1), (-1, -1, -1)],  # -x
    [(-1, 1, -1), (-1, 1, 1), (1, 1, 1), (1, 1, -1)],  # +y
    [(-1, -1, 1), (-1, -1, -1), (1, -1, -1), (1, -1, 1)],  # -y
    [(-1, -1, 1), (1, -1, 1), (1, 1, 1), (-1, 1, 1)],  # +z
    [(1, -1, -1), (-1, -1, -1), (-1, 1, -1), (1, 1, -1)],  # -z
]


def cube_mesh(shared: bool) -> Mesh:
    """Unit cube [-1,1]^3, 12 triangles. shared=True: the 8 corners are shared, so the course's
    averaging makes it shade like a blob; shared=False: 4 vertices per face (24), flat shading."""
    mesh = Mesh()
    index: dict[Vec3, int] = {}
    for corners in _CUBE_FACES:
        ids = []
        for p in corners:
            p = (float(p[0]), float(p[1]), float(p[2]))
            if shared:
                if p not in index:
                    index[p] = mesh.add_vertex(p)
                ids.append(index[p])
            else:
                ids.append(mesh.add_vertex(p))
        mesh.faces += [(ids[0], ids[1], ids[2]), (ids[0], ids[2], ids[3])]
    _check_outward(mesh)
    return mesh


def sphere_mesh(stacks: int = 24, slices: int = 48) -> Mesh:
    """UV sphere of radius 1 with shared vertices: one vertex per pole (triangle fans, so no
    degenerate faces) and stacks-1 rings of `slices` vertices. Also carries vt and vn lines so
    the loader's skip rules are exercised (the course reads vt and ignores vn)."""
    mesh = Mesh()

    def add(phi: float, theta: float, s: float, t: float) -> int:
        p = (math.sin(phi) * math.cos(theta), math.cos(phi), -math.sin(phi) * math.sin(theta))
        mesh.texcoords.append((s, t))
        mesh.normals.append(p)  # the exact normal; the course recomputes its own anyway
        return mesh.add_vertex(p)

    top = add(0.0, 0.0, 0.5, 1.0)
    rings = []
    for k in range(1, stacks):
        phi = math.pi * k / stacks
        rings.append([add(phi, 2 * math.pi * j / slices, j / slices, 1 - k / stacks)
                      for j in range(slices)])
    bottom = add(math.pi, 0.0, 0.5, 0.0)
    for j in range(slices):
        j1 = (j + 1) % slices
        mesh.faces.append((top, rings[0][j], rings[0][j1]))
        for k in range(stacks - 2):
            a, b = rings[k][j], rings[k][j1]
            c, d = rings[k + 1][j], rings[k + 1][j1]
            mesh.faces += [(a, c, d), (a, d, b)]
        mesh.faces.append((bottom, rings[-1][j1], rings[-1][j]))
    _check_outward(mesh)
    return mesh


def torus_mesh(major: float = 1.0, minor: float = 0.4, around: int = 36,
               tube: int = 18) -> Mesh:
    """Torus around the y axis with shared vertices (smooth under the averaging rule)."""
    mesh = Mesh()
    grid = [[mesh.add_vertex(((major + minor * math.cos(b)) * math.cos(a),
                              minor * math.sin(b),
                              -(major + minor * math.cos(b)) * math.sin(a)))
             for b in (2 * math.pi * j / tube for j in range(tube))]
            for a in (2 * math.pi * i / around for i in range(around))]
    for i in range(around):
        i1 = (i + 1) % around
        for j in range(tube):
            j1 = (j + 1) % tube
            a, b, c, d = grid[i][j], grid[i1][j], grid[i1][j1], grid[i][j1]
            mesh.faces += [(a, b, c), (a, c, d)]
    _check_torus_outward(mesh, major)
    return mesh


def _check_torus_outward(mesh: Mesh, major: float) -> None:
    """Outward for a torus means away from the nearest point of its core circle."""
    v = np.array(mesh.vertices)
    f = np.array(mesh.faces)
    a, b, c = v[f[:, 0]], v[f[:, 1]], v[f[:, 2]]
    n = np.cross(b - a, c - a)
    g = (a + b + c) / 3.0
    ring = g * np.array([1.0, 0.0, 1.0])
    core = ring / np.linalg.norm(ring, axis=1)[:, None] * major
    if ((n * (g - core)).sum(axis=1) <= 0).any() or (np.linalg.norm(n, axis=1) < 1e-9).any():
        raise AssertionError("bad triangle in generated torus")


# --------------------------------------------------------------------------------------------
# Cube map
# --------------------------------------------------------------------------------------------
# Per face: a distinct marker colour, so a wrong face choice shows as the wrong colour.
FACE_COLORS: dict[str, tuple[float, float, float]] = {
    "right": (0.95, 0.15, 0.15),  # +x red
    "left": (0.10, 0.85, 0.85),  # -x cyan
    "up": (0.15, 0.85, 0.15),  # +y green
    "down": (0.85, 0.15, 0.85),  # -y magenta
    "front": (0.15, 0.25, 0.95),  # +z blue
    "back": (0.95, 0.85, 0.10),  # -z yellow
}


def face_directions(face: str, size: int) -> np.ndarray:
    """(size, size, 3) world directions of the texel centres of a face, PNG row 0 at the top.

    This inverts the course's lookup table (spec §7), so the sky gradient computed from these
    directions is continuous across face seams when the lookup is right."""
    centres = (np.arange(size) + 0.5) / size
    u = np.broadcast_to(centres[None, :], (size, size))
    v = np.broadcast_to(1.0 - centres[:, None], (size, size))  # row 0 = top = v near 1
    a, b = 2 * u - 1, 2 * v - 1
    one = np.ones_like(a)
    comps = {
        "right": (one, b, a),
        "left": (-one, b, -a),
        "up": (a, one, b),
        "down": (a, -one, b),
        "front": (-a, b, one),
        "back": (-a, b, -one),
    }[face]
    d = np.stack(comps, axis=-1)
    return d / np.linalg.norm(d, axis=-1, keepdims=True)


def sky_color(d: np.ndarray) -> np.ndarray:
    """Smooth procedural sky: pale horizon to deep zenith blue above, brown ground below,
    with a slight warm tint towards +x so azimuth is visible in mirrors too."""
    y = d[..., 1:2]
    horizon = np.array([0.85, 0.88, 0.95])
    zenith = np.array([0.15, 0.35, 0.80])
    ground_near = np.array([0.45, 0.38, 0.30])
    ground_far = np.array([0.20, 0.16, 0.12])
    up = np.clip(y, 0, 1) ** 0.6
    down = np.clip(-y, 0, 1) ** 0.5
    sky = horizon * (1 - up) + zenith * up
    ground = ground_near * (1 - down) + ground_far * down
    col = np.where(y >= 0, sky, ground)
    warm = np.clip(d[..., 0:1], 0, 1) * np.array([0.10, 0.03, -0.08])
    return np.clip(col + warm, 0, 1)


def face_marker_mask(size: int) -> tuple[np.ndarray, np.ndarray]:
    """(grid, marker) boolean masks. The grid (lines every size/4 texels) shows face colour and
    scale; the marker is an asymmetric 'Γ' in the top-left corner (long vertical bar, short
    top bar) so flips, transposes and rotations of a face are all distinguishable."""
    idx = np.arange(size)
    step = size // 4
    line = (idx % step) == 0
    grid = line[:, None] | line[None, :]
    marker = np.zeros((size, size), dtype=bool)
    s = size / 64.0
    r0, r1 = int(6 * s), int(34 * s)  # vertical bar rows (long)
    c0, c1 = int(6 * s), int(12 * s)  # vertical bar columns
    marker[r0:r1, c0:c1] = True
    marker[r0:int(12 * s), c0:int(22 * s)] = True  # short top bar
    return grid, marker


def face_image(face: str, size: int = FACE_SIZE) -> np.ndarray:
    """8-bit RGB face: sky gradient, face-coloured grid blended at 50%, solid marker."""
    base = sky_color(face_directions(face, size))
    color = np.array(FACE_COLORS[face])
    grid, marker = face_marker_mask(size)
    img = np.where(grid[..., None], 0.5 * base + 0.5 * color, base)
    img = np.where(marker[..., None], color, img)
    return np.round(img * 255.0).astype(np.uint8)


def write_png(path: Path, rgb: np.ndarray) -> None:
    # Pillow writes no tIME/text chunks unless asked; a fixed compression level keeps the
    # zlib stream, and so the bytes, identical between runs.
    Image.fromarray(rgb, "RGB").save(path, format="PNG", compress_level=9, optimize=False)


# --------------------------------------------------------------------------------------------
# Driver
# --------------------------------------------------------------------------------------------
def write_text(path: Path, text: str) -> None:
    # newline="\n": the same bytes on every platform.
    with open(path, "w", encoding="ascii", newline="\n") as f:
        f.write(text)


def generate(out: Path) -> list[Path]:
    """Write every asset under out; returns the written paths."""
    out.mkdir(parents=True, exist_ok=True)
    written: list[Path] = []
    meshes = {
        "cube.obj": (cube_mesh(shared=True), [
            "Unit cube [-1,1]^3, 8 SHARED vertices, 12 triangles (generated by make_assets.py).",
            "The course averages face normals at shared vertices, so this cube shades smooth;",
            "use cube_flat.obj for flat-shaded boxes."], False),
        "cube_flat.obj": (cube_mesh(shared=False), [
            "Unit cube [-1,1]^3, 24 unshared vertices (4 per face), 12 triangles.",
            "Unshared vertices make the course's normal averaging give flat faces."], False),
        "sphere.obj": (sphere_mesh(), [
            "UV sphere, radius 1, 24 stacks x 48 slices, shared vertices (smooth).",
            "vt and vn lines are present but unused: the course ignores vn and recomputes",
            "normals; faces use the 'f a/ta b/tb c/tc' form."], True),
        "torus.obj": (torus_mesh(), [
            "Torus around the y axis, major radius 1, minor radius 0.4, 36 x 18 segments,",
            "shared vertices (smooth)."], False),
    }
    for name, (mesh, header, uv_faces) in meshes.items():
        path = out / name
        write_text(path, obj_text(mesh, header, uv_faces))
        written.append(path)
    sky = out / "sky"
    sky.mkdir(exist_ok=True)
    for face in FACE_COLORS:
        path = sky / f"{face}.png"
        write_png(path, face_image(face))
        written.append(path)
    return written


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=ASSETS, help=f"output folder (default {ASSETS})")
    args = ap.parse_args(argv)
    for path in generate(args.out):
        print(path)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
