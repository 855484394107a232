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


def mat3_mul(m, v):
    """m (3x3 nested sequence of host floats) times a traced vector, row by row."""
    return type(v)(
        (m[0][0] * v.x + m[0][1] * v.y) + m[0][2] * v.z,
        (m[1][0] * v.x + m[1][1] * v.y) + m[1][2] * v.z,
        (m[2][0] * v.x + m[2][1] * v.y) + m[2][2] * v.z,
    )
