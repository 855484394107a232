"""`course_whitted`: the course's deterministic Whitted shading (spec §6-8) as an integrator.

Mitsuba finds the hits (its own sphere, disk, mesh and instance code, through Embree on the
CPU); this integrator adds what Mitsuba lacks: the course's shading sum over every light in file
order, its shadow rule, its mirror recursion, its background and its normal and depth images.

    trace(ray, bounces):
      miss: background(ray.d)                     cube-map texel or the background colour
      hit:  sum over lights of shade(N, L, I)     unless -shadows and the shadow ray is blocked
            + ks * trace(reflected ray, bounces-1)  if |ks| > 0.1 and bounces > 0
            + ambient * kd

The recursion runs as one symbolic loop: `weight` is the product of the ks factors so far and
each level adds weight * (its local colour) -- the same sum, added in a different order.

Properties:
  bounces (int, 0), shadows (bool, false), ambient (rgb, 0), background (rgb, 0.5),
  cube_map (string: folder with the six faces; empty = none),
  offsets ("course" | "mitsuba"): where shadow and reflection rays start. "course" (default) is
      the course's p + 0.01 * dir with p = o + t*d; "mitsuba" uses Mitsuba's own
      SurfaceInteraction.spawn_ray / spawn_ray_to: an offset along the normal of about
      (1 + max|p|) * 9e-5, which treats contact points differently from the 0.01 rule.
  color (bool, true): false skips all shading (only the AOVs below are wanted);
  normals, depth (bool): add the AOVs "nx", "ny", "nz" = (n+1)/2 of the primary hit's normal
      (n = 0 on a miss, so 0.5) and "depth" = (t - depth_min)/(depth_max - depth_min)
      (t = FLT_MAX on a miss, which quantises to black); depth_min, depth_max (floats, 0 and 1).
"""
from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import SupportsFloat, SupportsInt, cast

import drjit as dr
import mitsuba as mi
import numpy as np

from . import bsdf as course_bsdf
from .cubemap import CubeMapLookup

FLT_MAX = float(np.finfo(np.float32).max)
COURSE_OFFSET = 0.01  # spec §6: shadow and reflection rays start at p + 0.01 * direction
OFFSET_MODES = ("course", "mitsuba")


def _rgb(props: mi.Properties, name: str, default: tuple[float, float, float]) -> list[float]:
    if name in props:
        c = cast("mi.ScalarColor3d", props.get(name))  # what Properties makes of an rgb
        return [float(c[0]), float(c[1]), float(c[2])]
    return list(default)


class CourseWhitted(mi.SamplingIntegrator):
    def __init__(self, props: mi.Properties) -> None:
        mi.SamplingIntegrator.__init__(self, props)
        self.bounces = int(cast(SupportsInt, props.get("bounces", 0)))
        self.shadows = bool(props.get("shadows", False))
        self.offsets = str(props.get("offsets", "course"))
        if self.offsets not in OFFSET_MODES:
            raise ValueError(f"course_whitted: offsets must be one of {OFFSET_MODES}, "
                             f"found '{self.offsets}'")
        self.ambient = _rgb(props, "ambient", (0.0, 0.0, 0.0))
        self.background = _rgb(props, "background", (0.5, 0.5, 0.5))
        folder = str(props.get("cube_map", ""))
        self.cube_map = None
        if folder:
            # resolve like Mitsuba's own plugins: relative to the XML file being loaded
            # the stubs have only Thread.file_resolver, not the module's own
            file_resolver = cast("Callable[[], mi.FileResolver]", mi.file_resolver)
            resolved = file_resolver().resolve(folder)
            self.cube_map = CubeMapLookup.from_folder(Path(str(resolved)))
        self.want_color = bool(props.get("color", True))
        self.want_normals = bool(props.get("normals", False))
        self.want_depth = bool(props.get("depth", False))
        self.depth_min = float(np.float32(cast(SupportsFloat, props.get("depth_min", 0.0))))
        self.depth_max = float(np.float32(cast(SupportsFloat, props.get("depth_max", 1.0))))

    def aov_names(self) -> list[str]:
        names = []
        if self.want_normals:
            names += ["nx", "ny", "nz"]
        if self.want_depth:
            names += ["depth"]
        return names

    # --- pieces of the shading model -------------------------------------------------------
    def background_color(self, d: mi.Vector3f, active: mi.Bool) -> mi.Color3f:
        if self.cube_map is not None:
            return self.cube_map.lookup(d, active)
        return mi.Color3f(*self.background)

    @staticmethod
    def lights(scene: mi.Scene) -> list[tuple[mi.Emitter, bool]]:
        """Emitters in file order (the translator names them light_000, light_001, ...), each
        with whether it is a directional light (any hit along its shadow ray blocks it)."""
        emitters = sorted(scene.emitters(), key=lambda e: e.id())
        return [(e, mi.has_flag(e.flags(), mi.EmitterFlags.Infinite)) for e in emitters]

    def shade(self, scene: mi.Scene, si: mi.SurfaceInteraction3f, p: mi.Point3f,
              n: mi.Normal3f, eye_d: mi.Vector3f, kd: mi.Color3f, ks: mi.Color3f,
              shininess: mi.Float, active: dr.auto.ad.Bool) -> mi.Color3f:
        """Sum over all lights of diffuse + specular at p (spec §6 `shade`)."""
        color = mi.Color3f(0.0)
        # mirrored eye ray, with N as stored (a bare plane's raw normal included); the stubs
        # lack Float * Normal3f
        r = eye_d - 2.0 * _dot(n, eye_d) * n  # type: ignore[operator]
        it = dr.zeros(mi.Interaction3f)
        it.p = p
        for emitter, directional in self.lights(scene):
            ds, intensity = emitter.sample_direction(it, mi.Point2f(0.5), active)
            l = ds.d
            lit = mi.Bool(active)
            if self.shadows:
                if self.offsets == "course":
                    # blocked by any hit at t <= distToLight (FLT_MAX for directional lights)
                    maxt = FLT_MAX if directional else ds.dist
                    # the stubs lack Point3f + Vector3f, and Ray3f taking a float maxt or time
                    # or rgb's Color0f wavelengths
                    shadow_ray = mi.Ray3f(  # type: ignore[call-overload]
                        p + COURSE_OFFSET * l,  # type: ignore[operator]
                        l, maxt, 0.0, mi.Color0f())
                elif directional:
                    shadow_ray = si.spawn_ray(l)
                else:
                    shadow_ray = si.spawn_ray_to(ds.p)
                lit &= ~scene.ray_test(shadow_ray, active)
            # the stubs lack Float * Spectrum
            diffuse = (dr.maximum(_dot(n, l), 0.0) * intensity) * kd  # type: ignore[operator]
            specular = (course_bsdf.powf(dr.maximum(_dot(r, l), 0.0), shininess)
                        * intensity) * ks  # type: ignore[operator]
            color[lit] = color + (diffuse + specular)
        return color

    # --- the integrator ------------------------------------------------------------------
    @dr.syntax
    def sample(self, scene: mi.Scene, sampler: mi.Sampler, ray: mi.Ray3f,
               medium: mi.Medium | None = None,
               active: mi.Bool | dr.auto.ad.Bool | bool = True):
        ray = mi.Ray3f(ray)
        active = mi.Bool(active)
        color = mi.Color3f(0.0)
        weight = mi.Color3f(1.0)      # product of the ks of the mirrors passed so far
        depth = mi.UInt32(0)
        first_n = mi.Normal3f(0.0)    # primary hit's normal, 0 on a miss (spec §8)
        first_t = mi.Float(FLT_MAX)   # primary hit's t, FLT_MAX on a miss
        ambient = mi.Color3f(*self.ambient)

        bounces = self.bounces if self.want_color else 0
        while dr.hint(active, max_iterations=bounces + 1, label="course_whitted"):
            # the stubs' Mitsuba functions take drjit.auto.ad.Bool masks, not their mi.Bool
            si = scene.ray_intersect(ray, mi.RayFlags.Minimal | mi.RayFlags.ShadingFrame,
                                     coherent=cast("dr.auto.ad.Bool", depth == 0),
                                     active=cast("dr.auto.ad.Bool", active))
            hit = cast("dr.auto.ad.Bool", active & si.is_valid())
            miss = active & ~si.is_valid()

            material = si.bsdf()
            n = si.sh_frame.n * material.eval_attribute_1("normal_scale", si, hit)
            first_n[hit & (depth == 0)] = n
            first_t[hit & (depth == 0)] = si.t

            kd = material.eval_attribute_3("kd", si, hit)
            ks = material.eval_attribute_3("ks", si, hit)
            # the course's hit point p = o + t*d (Mitsuba's si.p is re-projected onto the shape)
            p = ray.o + si.t * ray.d  # type: ignore[operator]  # stubs lack Point3f + Vector3f
            if dr.hint(self.want_color, mode="scalar"):
                color[miss] = color + weight * self.background_color(ray.d, miss)
                # our BSDF's mi.Float (the stubs: drjit.auto.ad.Float, another class to them)
                shininess = cast("mi.Float", material.eval_attribute_1("shininess", si, hit))
                local = self.shade(scene, si, p, n, ray.d, kd, ks, shininess, hit)
                local = local + ambient * kd
                color[hit] = color + weight * local

            # mirror recursion: |ks| > 0.1 and bounces left
            ks_len = dr.sqrt((ks.x * ks.x + ks.y * ks.y) + ks.z * ks.z)
            active = hit & (ks_len > course_bsdf.MIRROR_THRESHOLD) & (depth < bounces)
            # not renormalized (raw plane normals); the stubs lack Float * Normal3f
            r = ray.d - 2.0 * _dot(n, ray.d) * n  # type: ignore[operator]
            if dr.hint(self.offsets == "course", mode="scalar"):
                ray = mi.Ray3f(p + COURSE_OFFSET * r, r)
            else:
                ray = si.spawn_ray(r)
            weight *= ks
            depth += 1

        aovs = []
        if dr.hint(self.want_normals, mode="scalar"):
            half = (first_n + 1.0) / 2.0
            aovs += [half.x, half.y, half.z]
        if dr.hint(self.want_depth, mode="scalar"):
            lo = dr.opaque(mi.Float, self.depth_min)
            # the stubs' opaque(mi.Float, value) takes a float, not this numpy float32
            span = dr.opaque(mi.Float,  # type: ignore[misc]
                             np.float32(self.depth_max) - np.float32(self.depth_min))
            aovs += [(first_t - lo) / span]
        return color, mi.Bool(True), aovs

    def to_string(self) -> str:
        return (f"CourseWhitted[bounces={self.bounces}, shadows={self.shadows}, "
                f"offsets={self.offsets}, cube_map={self.cube_map is not None}, "
                f"aovs={self.aov_names()}]")


def _dot(a, b) -> mi.Float:
    """x*x' + y*y' + z*z' summed left to right, as the course's C++ does."""
    return (a.x * b.x + a.y * b.y) + a.z * b.z


mi.register_integrator("course_whitted", lambda props: CourseWhitted(props))
