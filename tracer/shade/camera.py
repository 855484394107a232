"""The course camera (spec §4): raw up vector, no aspect correction, edge pixels at ndc ±1."""
from __future__ import annotations

import ctypes
import math
from dataclasses import dataclass

import numpy as np

from ..scene.model import Camera

F32 = np.float32


def _libm_tanf():
    """The C library's tanf: from Python's own process, which links libm (ctypes.util's
    find_library runs ldconfig in a subprocess: ~5 ms of a render's start-up), else from libm
    found by name; None where there is none."""
    try:
        return ctypes.CDLL(None).tanf
    except (OSError, AttributeError):
        from ctypes.util import find_library

        name = find_library("m")
        try:
            return ctypes.CDLL(name).tanf if name else None
        except (OSError, AttributeError):
            return None


def _load_tanf():
    fn = _libm_tanf()
    if fn is None:
        return lambda x: F32(np.tan(F32(x)))
    fn.restype, fn.argtypes = ctypes.c_float, [ctypes.c_float]
    return lambda x: F32(fn(float(x)))


# The C library's tanf, as the course program calls it; numpy's float32 tan differs in the last
# bit for about a quarter of all angles.
tanf = _load_tanf()


def _normalize(v: np.ndarray) -> np.ndarray:
    with np.errstate(invalid="ignore", divide="ignore"):
        return (v / np.sqrt((v[0] * v[0] + v[1] * v[1]) + v[2] * v[2])).astype(F32)


@dataclass(frozen=True)
class CameraFrame:
    """Host-side float32 constants: dir(ndc) = normalize(forward + ndcx*right + ndcy*up)."""

    center: np.ndarray
    forward: np.ndarray  # dist * w
    right: np.ndarray  # u
    up: np.ndarray  # v, raw


@dataclass(frozen=True)
class FrameVectors:
    """The camera's float32 vectors as the course computes them (spec §4), quirks included:
    w and u NaN for a zero direction or an up parallel to it, dist inf for angle 0."""

    center: np.ndarray
    w: np.ndarray  # the direction, normalised
    u: np.ndarray  # normalize(direction x up)
    up: np.ndarray  # raw
    dist: np.float32  # 1 / tanf(angle / 2)
    angle: np.float32  # radians
    forward: np.ndarray  # dist * w


def frame_vectors(cam: Camera) -> FrameVectors:
    d = np.array(cam.direction, F32)
    up = np.array(cam.up, F32)
    w = _normalize(d)
    u = _normalize(np.cross(d, up).astype(F32))
    angle = F32(math.pi * cam.angle_deg / 180.0)
    # a quirk scene's angle makes dist inf (tan 0) and dist * w NaN, as in the course
    with np.errstate(divide="ignore", invalid="ignore"):
        dist = F32(1.0) / tanf(angle / F32(2.0))
        forward = (dist * w).astype(F32)
    return FrameVectors(np.array(cam.center, F32), w, u, up, dist, angle, forward)


def camera_frame(cam: Camera) -> CameraFrame:
    """The course's frame: its vectors as they are (robust.py: robust mode's frame)."""
    v = frame_vectors(cam)
    return CameraFrame(v.center, v.forward, v.u, v.up)
