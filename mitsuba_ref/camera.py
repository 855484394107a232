"""`course_camera`: a Mitsuba sensor reproducing the course's perspective camera (spec §4, §9).

Mitsuba's `perspective` sensor orthonormalizes its frame, corrects the aspect ratio, starts rays
on the near-clip plane and samples pixel centres at (x + 0.5)/w. The course camera does none of
that:

    w = normalize(direction), u = normalize(cross(direction, up)), v = up   (raw)
    dist = 1 / tanf(angle / 2)
    ndcx = 2 * (x / (W - 1.0f)) - 1,  ndcy = 2 * (y / (H - 1.0f)) - 1      (y = 0 is the BOTTOM row)
    ray  = (center, normalize(dist*w + ndcx*u + ndcy*v))

so edge pixels look along ndc = ±1 exactly, both axes span [-1, 1] whatever the aspect ratio, and
t is the Euclidean distance from the eye. Mitsuba's film has row 0 at the top, so film row r is
course row y = H - 1 - r.

`jitter = true` (`-jitter`) uses the sampler's sub-pixel offset: the course sample is
x + ξx, y + ξy with ξ uniform in [0, 1). Without it the offset is ignored and pixel x samples
exactly x. `-filter` needs nothing here: the film is simply 3w x 3h (spec §9), the 1-2-1 kernel is
applied after rendering (render.py).

Properties: center (point), direction, up (vectors), angle (degrees, float), jitter (bool,
default false), far_clip (float, default FLT_MAX: the course's initial t), film, sampler.
"""
from __future__ import annotations

import math
from typing import SupportsFloat, cast

import drjit as dr
import mitsuba as mi
import numpy as np

FLT_MAX = float(np.finfo(np.float32).max)
F32 = np.float32


def _vec(props: mi.Properties, name: str, default: tuple[float, float, float]) -> np.ndarray:
    if name in props:
        # Properties keeps a point or vector as a drjit.scalar.Array3f64; its stub says object
        v = cast("dr.scalar.Array3f64", props.get(name))
        return np.array([v[0], v[1], v[2]], dtype=F32)
    return np.array(default, dtype=F32)


def _normalize32(v: np.ndarray) -> np.ndarray:
    with np.errstate(all="ignore"):
        return v / np.sqrt((v[0] * v[0] + v[1] * v[1]) + v[2] * v[2])


def _cross32(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.array([a[1] * b[2] - a[2] * b[1],
                     a[2] * b[0] - a[0] * b[2],
                     a[0] * b[1] - a[1] * b[0]], dtype=F32)


def course_frame(direction: np.ndarray, up: np.ndarray, angle_deg: float
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.float32]:
    """(w, u, v, dist) of spec §4 in float32; the angle goes to radians in double first."""
    w = _normalize32(direction)
    u = _normalize32(_cross32(direction, up))
    radians = F32(math.pi * float(angle_deg) / 180.0)
    with np.errstate(all="ignore"):
        # float32 tan, correctly rounded from the double result (what tanf returns)
        dist = F32(1.0) / F32(math.tan(float(radians / F32(2.0)))) if math.isfinite(radians) \
            else F32("nan")
    return w, u, up.astype(F32), F32(dist)


class CourseCamera(mi.Sensor):
    def __init__(self, props: mi.Properties) -> None:
        mi.Sensor.__init__(self, props)
        self.center = _vec(props, "center", (0.0, 0.0, 0.0))
        self.direction = _vec(props, "direction", (0.0, 0.0, -1.0))
        self.up = _vec(props, "up", (0.0, 1.0, 0.0))
        self.angle = float(cast(SupportsFloat, props.get("angle", 90.0)))
        self.jitter = bool(props.get("jitter", False))
        self.far_clip = float(cast(SupportsFloat, props.get("far_clip", FLT_MAX)))
        self.w, self.u, self.v, self.dist = course_frame(self.direction, self.up, self.angle)
        # the sampler's 2D sample picks the film position (and, with jitter, the sub-pixel offset)
        self.m_needs_sample_2 = True
        self.m_needs_sample_3 = False

    def sample_ray(self, time, wavelength_sample, position_sample, aperture_sample,
                   active=True):
        film = self.film()
        width, height = (int(n) for n in film.size())
        crop_w, crop_h = (int(n) for n in film.crop_size())
        crop_x, crop_y = (int(n) for n in film.crop_offset())
        # Film coordinates: Mitsuba passes (pixel + ξ) / size within the crop window (the whole
        # film unless the image is rendered in bands), row 0 at the top.
        fx = position_sample.x * dr.opaque(mi.Float, crop_w)
        fy = position_sample.y * dr.opaque(mi.Float, crop_h)
        if crop_x or crop_y:  # only for bands: x + 0 would be the same bits anyway
            fx = fx + dr.opaque(mi.Float, crop_x)
            fy = fy + dr.opaque(mi.Float, crop_y)
        if self.jitter:
            # course x + ξx and y + ξy (y counted from the bottom: H - (row + ξ))
            px = fx
            py = dr.opaque(mi.Float, height) - fy
        else:
            # the sampler offset is 0.5 (stratified, no jitter): floor recovers the pixel
            px = dr.floor(fx)
            py = dr.opaque(mi.Float, height - 1) - dr.floor(fy)
        # (W - 1.0f) as a runtime value: a division by a literal would be turned into a
        # multiplication by its reciprocal, which is not the course's float division.
        ndcx = 2.0 * (px / dr.opaque(mi.Float, width - 1.0)) - 1.0
        ndcy = 2.0 * (py / dr.opaque(mi.Float, height - 1.0)) - 1.0
        w = mi.Vector3f(*self.w.tolist())
        u = mi.Vector3f(*self.u.tolist())
        v = mi.Vector3f(*self.v.tolist())
        d = (dr.opaque(mi.Float, float(self.dist)) * w + ndcx * u) + ndcy * v
        d = d / dr.sqrt((d.x * d.x + d.y * d.y) + d.z * d.z)  # spec: v / sqrt(v·v)
        ray = mi.Ray3f(mi.Point3f(*self.center.tolist()), d, self.far_clip, time,
                       mi.Color0f())
        return ray, mi.Spectrum(1.0)

    def sample_ray_differential(self, time, wavelength_sample, position_sample,
                                aperture_sample, active=True):
        ray, weight = self.sample_ray(time, wavelength_sample, position_sample,
                                      aperture_sample, active)
        return mi.RayDifferential3f(ray), weight

    def bbox(self):
        p = mi.ScalarPoint3f(*self.center.tolist())
        return mi.ScalarBoundingBox3f(p, p)

    def traverse(self, callback):
        pass  # nothing differentiable or editable: a course camera is fixed by the file

    def to_string(self) -> str:
        return (f"CourseCamera[center={self.center.tolist()}, direction="
                f"{self.direction.tolist()}, up={self.up.tolist()}, angle={self.angle}, "
                f"jitter={self.jitter}, far_clip={self.far_clip:g}]")


mi.register_sensor("course_camera", lambda props: CourseCamera(props))
