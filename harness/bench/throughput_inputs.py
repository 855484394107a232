"""The throughput benchmark's inputs (bench/throughput.py): bumpy UV spheres of any triangle
count with shared vertices and smooth vertex normals, the course camera that looks at them from
outside (about half of the rays hit; the rest miss through the BVH root), its primary rays in
the order a render casts them (16 consecutive rays are a 4x4 block of pixels,
``tracer.render.lane_positions``), and the mesh as the tracer's flat scene and as a course scene
for a full render."""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np

EYE = (0.9, 1.2, 3.3)
FOV_DEG = 40.0


def bumpy_sphere(triangles: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A UV sphere of about `triangles` triangles, radially displaced by a few sines, with
    shared vertices: (positions (V,3) float32, faces (F,3) int64, vertex normals (V,3) float32)."""
    rings = max(2, int(round(math.sqrt(triangles / 4))))
    segs = 2 * rings
    th = np.linspace(0.0, np.pi, rings + 1)
    ph = np.linspace(0.0, 2 * np.pi, segs, endpoint=False)
    t, p = np.meshgrid(th, ph, indexing="ij")
    r = 1.0 + 0.04 * np.sin(7 * t) * np.sin(9 * p) + 0.02 * np.sin(23 * t + 3 * p)
    pos = np.stack([r * np.sin(t) * np.cos(p), r * np.cos(t), r * np.sin(t) * np.sin(p)], -1)
    pos = pos.reshape(-1, 3)
    i = np.arange(rings)[:, None]
    j = np.arange(segs)[None, :]
    a = i * segs + j
    b = i * segs + (j + 1) % segs
    c, d = a + segs, b + segs
    faces = np.concatenate([np.stack([a, c, d], -1).reshape(-1, 3),
                            np.stack([a, d, b], -1).reshape(-1, 3)])
    fn = np.cross(pos[faces[:, 1]] - pos[faces[:, 0]], pos[faces[:, 2]] - pos[faces[:, 0]])
    normals = np.zeros_like(pos)
    for k in range(3):
        np.add.at(normals, faces[:, k], fn)
    length = np.linalg.norm(normals, axis=1, keepdims=True)
    normals = np.where(length > 0, normals / np.where(length > 0, length, 1.0), pos)
    return pos.astype(np.float32), faces, normals.astype(np.float32)


def camera():
    """The course camera looking at the mesh from EYE, towards the origin."""
    from raycheck.tracer.scene.model import Camera

    eye = np.array(EYE)
    return Camera(tuple(eye.tolist()), tuple((-eye).tolist()), (0.0, 1.0, 0.0), FOV_DEG)


def camera_rays(res: int) -> tuple[np.ndarray, np.ndarray]:
    """The course camera's primary rays for a res x res image (as tracer.render builds them,
    in its lane order): origins and unit directions, (res*res, 3) float32 each."""
    from raycheck.tracer.render import lane_positions
    from raycheck.tracer.shade.camera import camera_frame

    f = camera_frame(camera())
    k = np.arange(res, dtype=np.float32)
    ndc = np.float32(2.0) * (k / np.float32(res - 1)) - np.float32(1.0)
    nx, ny = np.meshgrid(ndc, ndc)
    d = (f.forward[None, :] + nx.reshape(-1, 1) * f.right[None, :]) + ny.reshape(-1, 1) * f.up
    d = (d / np.sqrt((d * d).sum(axis=1, keepdims=True))).astype(np.float32)
    d = d[lane_positions(res, res)]
    o = np.broadcast_to(f.center, d.shape).astype(np.float32)
    return o, d


def flat_scene(pos, faces, normals):
    from raycheck.tracer.accel.flat_scene import FlatScene, TriangleSoup

    n = len(faces)
    soup = TriangleSoup(pos[faces], normals[faces], np.zeros(n, np.uint32),
                        np.arange(n, dtype=np.uint32))
    return FlatScene([], [], soup, n)


def course_scene(pos, faces, normals):
    from raycheck.tracer.scene.model import (
        Background,
        DirectionalLight,
        Group,
        Material,
        Mesh,
        PointLight,
        Scene,
    )

    mesh = Mesh(Path("bumpy_sphere"), pos, faces, normals, 0)
    lights = (DirectionalLight((-0.4, -0.7, -0.6), (0.8, 0.8, 0.8)),
              PointLight((2.0, 3.0, 2.5), (0.6, 0.6, 0.6), 0.05))
    return Scene(Path("bumpy_sphere"), camera(), lights,
                 Background((0.1, 0.1, 0.15), (0.1, 0.1, 0.1)),
                 (Material((0.7, 0.6, 0.5), (0.3, 0.3, 0.3), 30.0),), Group((mesh,)))
