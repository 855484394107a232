"""The flat index a pixel's value is read from, and the forms a mistake gives it.

Renderer::Render keeps a render's values in buffers of w x h values, row by row, rows counted
from the bottom (spec §9): an unfiltered output pixel (x, y) is read from index y * w + x, a
-filter tap (i, j) of output pixel (x, y) from (3 * y + j) * w + 3 * x + i of the buffer at
three times the size. Mutation testing's operators for C (arithmetic operator replacement,
constant replacement, an operand left out, one variable for another) turn an index expression
into others: y / w + x reads row 0 for every row, x * w + y transposes a square image. Each
form is a value of the INDEX operator at its site (operators.py), computed by the host after
the kernel (render.py), where the C program's integer arithmetic is exact.

    OUTPUT_FORMS[0].text                         # 'y * w + x'
    indices(OUTPUT_FORMS[k], w=4, h=4, ...)      # the index of every pixel, or None
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

ARITHMETIC = ("+", "-", "*", "/", "%")
PRECEDENCE = {"+": 1, "-": 1, "*": 2, "/": 2, "%": 2}
# One variable read for another: the row and the column swapped, the height for the width
SWAPS = ({"x": "y", "y": "x"}, {"w": "h"})


@dataclass(frozen=True)
class Form:
    """One index expression: a tree of (operator, left, right) with variable names and integer
    constants at its leaves."""

    tree: object

    @property
    def text(self) -> str:
        return _text(self.tree)


def _text(tree, parent: int = 0, right: bool = False) -> str:
    if not isinstance(tree, tuple):
        return str(tree)
    op, a, b = tree
    p = PRECEDENCE[op]
    s = f"{_text(a, p)} {op} {_text(b, p, True)}"
    # a right operand of equal precedence needs its parentheses: a - (b + c)
    return f"({s})" if p < parent or (right and p == parent) else s


def _mutants(tree) -> list:
    """Every tree one operator makes of `tree`: an arithmetic operator replaced, a constant
    replaced (0, 1, -1, itself plus or minus one, negated), an operand of a sum left out."""
    if isinstance(tree, int):
        return sorted({0, 1, -1, tree + 1, tree - 1, -tree} - {tree})
    if isinstance(tree, str):
        return []
    op, a, b = tree
    out = [(other, a, b) for other in ARITHMETIC if other != op]
    if op in "+-":
        out += [a] if op == "-" else [a, b]
    out += [(op, m, b) for m in _mutants(a)]
    out += [(op, a, m) for m in _mutants(b)]
    return out


def _renamed(tree, names: dict[str, str]):
    if isinstance(tree, str):
        return names.get(tree, tree)
    if isinstance(tree, tuple):
        op, a, b = tree
        return op, _renamed(a, names), _renamed(b, names)
    return tree


def forms(course) -> tuple[Form, ...]:
    """The course's form first, then its mutants, each text once (a mutant that reads as the
    course's, or as an earlier one, is left out)."""
    seen: dict[str, Form] = {}
    for tree in [course, *_mutants(course), *(_renamed(course, s) for s in SWAPS)]:
        seen.setdefault(Form(tree).text, Form(tree))
    return tuple(seen.values())


OUTPUT_FORMS = forms(("+", ("*", "y", "w"), "x"))
TAP_FORMS = forms(("+", ("+", ("*", ("+", ("*", 3, "y"), "j"), "w"), ("*", 3, "x")), "i"))


def _evaluate(tree, values: dict[str, np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """(value, defined): C's int arithmetic (division truncates towards zero, % takes the
    dividend's sign); undefined where it divides by zero."""
    if isinstance(tree, str):
        v = values[tree]
        return v, np.ones(v.shape, bool)
    if isinstance(tree, int):
        return np.asarray(tree, np.int64), np.ones((), bool)
    op, a, b = tree
    (x, dx), (y, dy) = _evaluate(a, values), _evaluate(b, values)
    x, y = np.broadcast_arrays(np.asarray(x, np.int64), np.asarray(y, np.int64))
    defined = dx & dy
    if op == "+":
        return x + y, defined
    if op == "-":
        return x - y, defined
    if op == "*":
        return x * y, defined
    safe = np.where(y == 0, 1, y)
    quotient = np.abs(x) // np.abs(safe) * np.sign(x) * np.sign(safe)
    defined = defined & (y != 0)
    return (quotient, defined) if op == "/" else (x - safe * quotient, defined)


def read_index(form: Form, **values: np.ndarray | int) -> tuple[np.ndarray, np.ndarray]:
    """(index, defined): the flat index the form gives at every combination of the variables'
    values (broadcast, as int64 arrays; 0 where undefined) and where the C program's read is
    defined: no division by zero, inside the buffer of w * h values."""
    arrays = {k: np.asarray(v, np.int64) for k, v in values.items()}
    index, defined = _evaluate(form.tree, arrays)
    shape = np.broadcast_shapes(*(a.shape for a in arrays.values()))
    index, defined = np.broadcast_to(index, shape), np.broadcast_to(defined, shape)
    defined = defined & (index >= 0) & (index < int(arrays["w"]) * int(arrays["h"]))
    return np.where(defined, index, 0), defined


def indices(form: Form, **values: np.ndarray | int) -> np.ndarray | None:
    """The flat index the form gives at every combination of the variables' values (broadcast,
    as int64 arrays), or None where the C program would read outside the buffer of w * h
    values or divide by zero there: its image is not defined."""
    index, defined = read_index(form, **values)
    return index if defined.all() else None


def output_read(v: np.ndarray, form: Form) -> tuple[np.ndarray, np.ndarray]:
    """(image, defined): the image written from the buffer `v` (rows from the top, as arrays
    hold images), each pixel (x, y) read at the form's index, and where that read is defined
    (elsewhere the image holds the buffer's first value)."""
    h, w = v.shape[:2]
    y, x = np.mgrid[0:h, 0:w]
    index, defined = read_index(form, x=x, y=y, w=w, h=h)
    flat = v[::-1].reshape((h * w,) + v.shape[2:])
    return flat[index][::-1], defined[::-1]


def read_output(v: np.ndarray, form: Form) -> np.ndarray | None:
    """output_read's image, None where any of its reads is undefined."""
    image, defined = output_read(v, form)
    return image if defined.all() else None


def taps_read(buffer: np.ndarray, form: Form, kernel, divisor: float, size: tuple[int, int]
              ) -> tuple[np.ndarray, np.ndarray]:
    """(image, defined): the -filter image of size (w, h) made from `buffer` (rows from the top;
    the form's w and h are the buffer's), each tap (i, j) of output pixel (x, y) read at the
    form's index, Σ_j Σ_i K[j][i]·tap / divisor in the course's order, and where each of a
    pixel's taps is defined."""
    big_h, big_w = buffer.shape[:2]
    w, h = size
    y, x = np.mgrid[0:h, 0:w]
    flat = buffer[::-1].reshape((big_h * big_w,) + buffer.shape[2:])
    out, defined = None, np.ones((h, w), bool)
    for j in range(3):
        for i in range(3):
            index, ok = read_index(form, x=x, y=y, i=i, j=j, w=big_w, h=big_h)
            term = flat[index][::-1] * buffer.dtype.type(kernel[j][i])
            out, defined = (term if out is None else out + term), defined & ok[::-1]
    assert out is not None
    return out / buffer.dtype.type(divisor), defined


def filter_taps(big: np.ndarray, form: Form, kernel, divisor: float) -> np.ndarray | None:
    """The -filter image of `big` (three times the size, rows from the top) with each tap (i, j)
    of output pixel (x, y) read at the form's index, Σ_j Σ_i K[j][i]·tap / divisor in the
    course's order; None where the index is undefined."""
    image, defined = taps_read(big, form, kernel, divisor, (big.shape[1] // 3, big.shape[0] // 3))
    return image if defined.all() else None
