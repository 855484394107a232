"""`course_phong`: the course material (spec §2 Materials, §6 shade) as a Mitsuba BSDF.

Mitsuba has no Phong BSDF (and its `diffuse` divides by pi), so the material is a plugin whose
parameters the Whitted integrator reads through the attribute interface:

    bsdf.eval_attribute_3("kd" | "ks", si)         diffuseColor, specularColor
    bsdf.eval_attribute_1("shininess", si)
    bsdf.eval_attribute_1("normal_scale", si)      length of a bare plane's normal as written

`normal_scale` exists because the course uses a bare plane's normal exactly as written (not
normalized: `normal 0 2 0` doubles the diffuse term and shows as byte 255 in the normals image),
while Mitsuba's disk (our plane) only knows a unit normal. The translator gives such a plane its
own copy of the material with normal_scale = |n|; every other shape uses 1.

For Mitsuba's own integrators the BSDF also answers `eval` with the course's response to a unit
light in direction wo (diffuse max(N·L,0) kd plus specular max(R·L,0)^s ks, not gated by N·L) and
`sample` with the mirror direction weighted by ks where |ks| > 0.1 (the course's mirror rule).
It is not energy conserving: it is the course's model, not a physical one.
"""
from __future__ import annotations

from typing import Any, cast

import drjit as dr
import mitsuba as mi

MIRROR_THRESHOLD = 0.1  # spec §6: a material reflects when |ks| > 0.1


def _color(props: mi.Properties, name: str, default: tuple[float, float, float]) -> mi.Color3f:
    if name in props:
        c: Any = props.get(name)  # what the file gave: an rgb or a texture (or anything)
        try:  # an `rgb` property arrives as a ScalarColor3f, a texture dict as a texture
            return mi.Color3f(float(c[0]), float(c[1]), float(c[2]))
        except TypeError:
            raise ValueError(f"course_phong: '{name}' must be an rgb value") from None
    return mi.Color3f(*default)


def powf(base: mi.Float, exponent: mi.Float) -> mi.Float:
    """C powf for base >= 0: powf(x, 0) = 1 (also for x = 0), powf(1, e) = 1,
    powf(0, e > 0) = 0, powf(0, e < 0) = inf, underflow 0. Evaluated in double and rounded
    once, close to a correctly rounded powf; Dr.Jit's float32 power (exp2(log2(x)·e)) is NaN
    for 0^0 and off by many ulp."""
    # NaN stays NaN (the stubs type power() of two arrays as object)
    p64 = cast("mi.Float64", dr.power(mi.Float64(base), mi.Float64(exponent)))
    # Dr.Jit 1.5 returns -inf for results in double's subnormal range (about 1e-308); a positive
    # base cannot give a negative power, and anything that small is 0 in float32
    p = mi.Float(dr.select(p64 < 0, 0.0, p64))
    at_zero = dr.select(exponent > 0, 0.0, dr.select(exponent < 0, dr.inf, 1.0))
    p = dr.select(base == 0, at_zero, p)
    return dr.select((exponent == 0) | (base == 1), 1.0, p)


class CoursePhong(mi.BSDF):
    def __init__(self, props: mi.Properties) -> None:
        mi.BSDF.__init__(self, props)
        self.kd = _color(props, "kd", (1.0, 1.0, 1.0))
        self.ks = _color(props, "ks", (0.0, 0.0, 0.0))
        self.shininess = mi.Float(props.get("shininess", 0.0))
        self.normal_scale = mi.Float(props.get("normal_scale", 1.0))
        ks = [float(self.ks.x[0]), float(self.ks.y[0]), float(self.ks.z[0])]
        self.mirror = (ks[0] * ks[0] + ks[1] * ks[1] + ks[2] * ks[2]) ** 0.5 > MIRROR_THRESHOLD
        flags = mi.BSDFFlags.DiffuseReflection | mi.BSDFFlags.GlossyReflection
        if self.mirror:
            flags |= mi.BSDFFlags.DeltaReflection
        self.m_components = [flags]
        self.m_flags = flags

    # --- what the Whitted integrator reads ------------------------------------------------
    def eval_attribute_3(self, name, si, active=True):
        if name == "kd":
            return mi.Color3f(self.kd)
        if name == "ks":
            return mi.Color3f(self.ks)
        return mi.Color3f(0.0)

    def eval_attribute_1(self, name, si, active=True):
        if name == "shininess":
            return mi.Float(self.shininess)
        if name == "normal_scale":
            return mi.Float(self.normal_scale)
        return mi.Float(0.0)

    def eval_attribute(self, name, si, active=True):
        return self.eval_attribute_3(name, si, active)

    def has_attribute(self, name, active=True):
        return mi.Bool(name in ("kd", "ks", "shininess", "normal_scale"))

    # --- a Mitsuba-facing reading of the same model -------------------------------------------
    def eval(self, ctx, si, wo, active=True):
        # local frame: N = (0, 0, 1); the eye ray arrives along -wi, so R = reflect(-wi)
        cos_l = mi.Frame3f.cos_theta(wo)
        r = mi.Vector3f(si.wi.x * -1.0, si.wi.y * -1.0, si.wi.z)
        diffuse = dr.maximum(cos_l, 0.0) * self.kd
        specular = powf(dr.maximum(dr.dot(r, wo), 0.0), self.shininess) * self.ks
        return dr.select(active, diffuse + specular, 0.0)

    def pdf(self, ctx, si, wo, active=True):
        return mi.Float(0.0)

    def eval_pdf(self, ctx, si, wo, active=True):
        return self.eval(ctx, si, wo, active), mi.Float(0.0)

    def sample(self, ctx, si, sample1, sample2, active=True):
        bs = dr.zeros(mi.BSDFSample3f)
        if not self.mirror:
            return bs, mi.Color3f(0.0)
        bs.wo = mi.reflect(si.wi)
        bs.pdf = mi.Float(1.0)
        bs.eta = mi.Float(1.0)
        bs.sampled_type = mi.UInt32(+mi.BSDFFlags.DeltaReflection)
        bs.sampled_component = mi.UInt32(0)
        return bs, dr.select(active, self.ks, 0.0)

    def traverse(self, callback):
        callback.put("kd", self.kd, mi.ParamFlags.NonDifferentiable)
        callback.put("ks", self.ks, mi.ParamFlags.NonDifferentiable)

    def to_string(self) -> str:
        return (f"CoursePhong[kd={self.kd}, ks={self.ks}, shininess={self.shininess}, "
                f"normal_scale={self.normal_scale}]")


mi.register_bsdf("course_phong", lambda props: CoursePhong(props))
