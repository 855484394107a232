"""The index forms of tracer/pixel_index.py: the mutants of the course's index expressions,
C's integer arithmetic, and the images a form reads, worked out by hand on tiny buffers (rows
counted from the bottom, as the course's buffers hold them; arrays hold row 0 at the top)."""
from __future__ import annotations

import numpy as np

from raycheck.tracer.pixel_index import (
    OUTPUT_FORMS,
    TAP_FORMS,
    Form,
    filter_taps,
    indices,
    output_read,
    read_output,
    taps_read,
)
from raycheck.tracer.render import FILTER_KERNEL, box_filter_3x3


def test_the_output_index_forms_are_its_one_operator_mutants():
    # the + replaced (4), each of its operands left out (2), the * replaced (4), x and y
    # swapped, h for w
    assert [f.text for f in OUTPUT_FORMS] == [
        "y * w + x", "y * w - x", "y * w * x", "y * w / x", "y * w % x", "y * w", "x",
        "y + w + x", "y - w + x", "y / w + x", "y % w + x", "x * w + y", "y * h + x"]


def test_the_tap_forms_start_with_the_course_and_print_with_cs_precedence():
    texts = [f.text for f in TAP_FORMS]
    assert texts[0] == "(3 * y + j) * w + 3 * x + i"
    assert len(texts) == len(set(texts)) == 45
    assert "(3 * y + j) * w - 3 * x + i" in texts  # a right operand needs no parentheses
    assert "(3 * y + j) * w + (3 - x) + i" in texts  # ... unless it is a sum itself
    assert "((3 * y + j) * w + 3 * x) / i" in texts
    assert "(3 * x + j) * w + 3 * y + i" in texts


def test_division_truncates_towards_zero_and_the_remainder_takes_the_dividends_sign():
    x = np.array([-7, 7])
    assert indices(Form(("+", ("/", "x", 2), 10)), x=x, w=100, h=1).tolist() == [7, 13]
    assert indices(Form(("+", ("%", "x", 2), 1)), x=x, w=100, h=1).tolist() == [0, 2]


def test_an_index_out_of_the_buffer_or_a_division_by_zero_is_undefined():
    assert indices(Form(("/", 5, "x")), x=np.array([0, 1]), w=10, h=1) is None
    assert indices(Form(("-", "x", 1)), x=np.array([0, 1]), w=10, h=1) is None
    assert indices(Form(("+", "x", 9)), x=np.array([0, 1]), w=10, h=1) is None
    assert indices(Form(("+", "x", 8)), x=np.array([0, 1]), w=10, h=1).tolist() == [8, 9]


def test_the_course_forms_read_every_pixel_where_it_is():
    rng = np.random.default_rng(5)
    v = rng.random((4, 5, 3)).astype(np.float32)
    assert np.array_equal(read_output(v, OUTPUT_FORMS[0]), v)
    big = rng.random((6, 9, 3)).astype(np.float32)
    assert np.array_equal(filter_taps(big, TAP_FORMS[0], FILTER_KERNEL, 16.0),
                          box_filter_3x3(big))


def test_mutated_forms_read_the_pixels_worked_out_by_hand():
    v = np.array([[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]])  # top row 1 2 3, bottom row 4 5 6
    # y / w + x: y < w, so every row reads row 0, the bottom one
    assert read_output(v, _form(OUTPUT_FORMS, "y / w + x")).tolist() == [[4, 5, 6], [4, 5, 6]]
    # y % w + x: row y reads from index y + x on: the top row is the bottom row moved one left
    assert read_output(v, _form(OUTPUT_FORMS, "y % w + x")).tolist() == [[5, 6, 1], [4, 5, 6]]
    # x * w + y on a square buffer: the transpose about the bottom-left corner
    square = np.array([[1.0, 2.0], [3.0, 4.0]])
    assert read_output(square, _form(OUTPUT_FORMS, "x * w + y")).tolist() == [[4, 2], [3, 1]]
    assert read_output(v, _form(OUTPUT_FORMS, "y * w - x")) is None  # y = 0, x = 1: index -1
    # each tap three sub-pixels to the right: pixel x filters the block that starts at 3 + x
    big = np.arange(27.0).reshape(3, 9)
    shifted = filter_taps(big, _form(TAP_FORMS, "(3 * y + j) * w + (3 + x) + i"),
                          FILTER_KERNEL, 16.0)
    assert shifted.tolist() == [[box_filter_3x3(big[:, 3 + x:6 + x])[0, 0] for x in range(3)]]


def test_a_form_that_reads_outside_the_buffer_somewhere_is_defined_elsewhere():
    """y * w - x on the 2x3 buffer: the bottom row's x = 1 and 2 read indices -1 and -2; every
    other pixel reads inside (the top row, y = 1, reads 3, 2, 1: the bottom row reversed, one
    along)."""
    v = np.array([[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]])
    image, defined = output_read(v, _form(OUTPUT_FORMS, "y * w - x"))
    assert defined.tolist() == [[True, True, True], [True, False, False]]
    assert image[defined].tolist() == [1.0, 6.0, 5.0, 4.0]


def test_the_filter_path_on_a_buffer_of_the_images_own_size_reads_its_lower_third():
    """The course's tap form on a 3x6 buffer for a 3x6 image (w = 3: the -filter path taken
    without -filter): pixel (x, 0) filters the 3x3 block of indices 3x + 3j + i (rows 0-2 at
    x = 0, rows 1-3 at x = 1, 2-4 at x = 2: inside the 18 values); at y = 1 only x = 0 stays
    inside (indices 9 to 17); from y = 2 on every tap reads from 18 on: undefined."""
    buffer = np.arange(18.0).reshape(6, 3)[::-1]  # index y * 3 + x holds y * 3 + x
    image, defined = taps_read(buffer, TAP_FORMS[0], FILTER_KERNEL, 16.0, (3, 6))
    tap = np.array(FILTER_KERNEL, float)

    def pixel(x: int, y: int) -> float:
        return sum(tap[j, i] * ((3 * y + j) * 3 + 3 * x + i)
                   for j in range(3) for i in range(3)) / 16.0

    bottom_up = defined[::-1]
    assert bottom_up.tolist() == [[True] * 3, [True, False, False], *[[False] * 3] * 4]
    assert image[::-1][0].tolist() == [pixel(x, 0) for x in range(3)]
    assert image[::-1][1, 0] == pixel(0, 1)


def _form(forms: tuple[Form, ...], text: str) -> Form:
    return next(f for f in forms if f.text == text)
