"""Vector helpers written as the course's float formulas, operation for operation.

Dr.Jit's own dr.dot / dr.normalize may reorder or use reciprocal square roots; the course
renderer computes these literally, and bit-level agreement needs the same order here.
"""
from __future__ import annotations

from dataclasses import dataclass
from types import ModuleType
from typing import Any

from .backend import array_namespace, import_drjit


@dataclass(frozen=True)
class Types:
    """The Dr.Jit array types one render uses (backend x precision)."""

    backend: str
    precision: str
    Float: Any
    Array3f: Any
    UInt32: Any
    Int32: Any
    Bool: Any
    PCG32: Any
    Float64: Any
    ns: ModuleType

    @property
    def np_float(self) -> str:
        return "float32" if self.precision == "single" else "float64"


def make_types(backend: str = "llvm", precision: str = "single") -> Types:
    ns = array_namespace(backend, precision)
    if precision == "single":
        return Types(backend, precision, ns.Float, ns.Array3f, ns.UInt32, ns.Int32, ns.Bool,
                     ns.PCG32, ns.Float64, ns)
    return Types(backend, precision, ns.Float64, ns.Array3f64, ns.UInt32, ns.Int32, ns.Bool,
                 ns.PCG32, ns.Float64, ns)


def gather_packet(types: Types, source, n: int, index):
    """Floats n·index .. n·index + n - 1 of source: one n-wide packet load per lane (source
    64-byte aligned, n = 4, 8 or 16)."""
    dr = import_drjit()
    xf = types.ns.ArrayXf if types.precision == "single" else types.ns.ArrayXf64
    return dr.gather(xf, source, index, shape=(n, dr.width(index)))


def float_bits(types: Types, x):
    """The uint32 bits a record's float slot holds (in float64 records: the integer's value)."""
    dr = import_drjit()
    return dr.reinterpret_array(types.UInt32, x) if types.precision == "single" \
        else types.UInt32(x)


def dot(a, b):
    return (a.x * b.x + a.y * b.y) + a.z * b.z


def cross(a, b):
    return type(a)(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x)


def div3(v, s):
    """v / s per component. Dr.Jit turns Array3f / Float into one reciprocal and three
    multiplications (1 ulp off in a quarter of the cases); the course divides three times."""
    return type(v)(v.x / s, v.y / s, v.z / s)


def normalize(v):
    dr = import_drjit()
    return div3(v, dr.sqrt(dot(v, v)))


FLT_MIN_NORMAL = 2.0**-126


def round_f32_subnormal(x):
    """A float64 array rounded to the float32 value the course's arithmetic gives, subnormals
    included, kept in float64. Dr.Jit's worker threads flush float32 subnormals to zero (inputs
    and results: nanothread sets FTZ/DAZ); a float32 subnormal is a normal float64, and below
    2^-126 float32 values are the multiples of 2^-149, rounded to even as the hardware does."""
    dr = import_drjit()
    tiny = dr.abs(x) < FLT_MIN_NORMAL
    sub = dr.round(x * 2.0**149) * 2.0**-149  # dr.round: ties to even
    return dr.select(tiny, sub, type(x)(dr.float32_array_t(type(x))(x)))


def homogeneous(m, o):
    """m (4x4 nested sequence, row-major) times the point (o, 1): (xyz, w)."""
    p = mat3_mul(m, o)
    p = type(o)(p.x + m[0][3], p.y + m[1][3], p.z + m[2][3])
    return p, ((m[3][0] * o.x + m[3][1] * o.y) + m[3][2] * o.z) + m[3][3]


def inverse_ray(m, o, d):
    """The ray (o, d) through one Transform level's inverse m (4x4 nested sequence of host
    floats or traced values, row-major): o' = m(o,1) divided by w, d' = m3x3·d (spec §5)."""
    p, w = homogeneous(m, o)
    return div3(p, w), mat3_mul(m, d)


def mat3_mul(m, v):
    """m (3x3 nested sequence of host floats) times a traced vector, row by row."""
    return type(v)(
        (m[0][0] * v.x + m[0][1] * v.y) + m[0][2] * v.z,
        (m[1][0] * v.x + m[1][1] * v.y) + m[1][2] * v.z,
        (m[2][0] * v.x + m[2][1] * v.y) + m[2][2] * v.z,
    )


# --- robust mode (--mode robust) helpers ------------------------------------------------------
# Ray origins for shadow and mirror rays: an error-bound offset in the spirit of pbrt-v4 (the hit
# point p = o + t*d is off the surface by at most about ERROR_ULPS * eps * (|o|_max + t)), then
# Wächter and Binder's integer-ULP step ("A Fast and Robust Method for Avoiding
# Self-Intersection", Ray Tracing Gems ch. 6; origin 1/32, float_scale 1/65536) so that the final
# rounding cannot undo the move. Their int_scale of 256 ulps was measured too large here: 2 units
# at 1e5 in float32, which lifts shadow rays over nearby blockers (light leaks; offset_1e5 SSIM
# 0.85); with the bound below both acne and leaks are gone.
ERROR_ULPS = 6.0
OFFSET_ORIGIN = 1.0 / 32.0
OFFSET_FLOAT_SCALE = 1.0 / 65536.0
OFFSET_INT_SCALE = 4.0


def normalize_safe(v):
    """normalize(v), but a zero (or non-finite-length) vector gives zero instead of NaN.
    Fixes: NaN normals and directions from degenerate geometry (0/0)."""
    dr = import_drjit()
    s = dr.sqrt(dot(v, v))
    ok = (s > 0.0) & dr.isfinite(s)
    z = dr.zeros(type(v), dr.width(s))
    return dr.select(ok, div3(v, dr.select(ok, s, 1.0)), z)


def offset_ray_origin(p, n, types: Types, scale=None):
    """p moved off the surface along the unit geometric normal n (already flipped toward the
    side the new ray leaves): first by ERROR_ULPS * eps * scale (scale = |o|_max + t of the ray
    that found p: a bound on p's rounding error), then by OFFSET_INT_SCALE * n_i ulps of each
    coordinate (Wächter and Binder). Fixes: shadow acne and self-hits of the course's fixed
    p + 0.01*dir, which is too small far from the origin (1e5: float32 spacing 0.008) and far
    too large for small scenes (1e-3: shadows and near reflections vanish)."""
    dr = import_drjit()
    single = types.precision == "single"
    Int = types.Int32 if single else types.ns.Int64
    if scale is not None:
        eps = 2.0**-24 if single else 2.0**-53
        delta = (ERROR_ULPS * eps) * dr.select(dr.isfinite(scale), scale, 0.0)
        p = p + n * delta
    out = []
    for pi, ni in ((p.x, n.x), (p.y, n.y), (p.z, n.z)):
        of = Int(ni * OFFSET_INT_SCALE)  # truncation toward zero, as the paper's int cast
        bits = dr.reinterpret_array(Int, pi)
        moved = dr.reinterpret_array(type(pi), bits + dr.select(pi < 0.0, -of, of))
        out.append(dr.select(dr.abs(pi) < OFFSET_ORIGIN, pi + OFFSET_FLOAT_SCALE * ni, moved))
    return type(p)(*out)
