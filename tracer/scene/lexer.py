"""Tokens of the course scene format: maximal runs of non-whitespace, with line numbers.

One closing brace glued to the end of a number (`shininess 20}`) becomes its own token, as the
reference reads it (it reads a number, then a token: `20}}` leaves `}}`, which is not a brace,
and is an error here too). `#` starts a comment running to the end of the line: an extension (the
reference has no comment syntax) that lets our scene files say what they probe.

Robustness rules (the reference is a C program reading with the C library):
* whitespace is C's isspace() in the "C" locale (space, \t, \n, \v, \f, \r); other Unicode
  spaces are part of a token, and lines are counted by '\n' only;
* digits are ASCII digits: the number patterns are unambiguous, so matching is linear in the
  token length (no catastrophic backtracking on a 16 MiB run of digits);
* words such as `nan`, `inf` or `0x10` are not numbers; a number too large for float32
  (`1e39`) becomes ±inf and a too small one 0, as C's strtof gives (see parser.f32);
* an integer (count or index) has at most MAX_INT_DIGITS digits.
"""
from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path
from typing import Iterable, Iterator

from .errors import SceneError, quote

FLOAT_RE = re.compile(r"[+-]?(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)(?:[eE][+-]?[0-9]+)?")
INT_RE = re.compile(r"[+-]?[0-9]+")
_GLUED_RE = re.compile(r"(" + FLOAT_RE.pattern + r")\}")
_BRACES_RE = re.compile(r"(" + FLOAT_RE.pattern + r")\}{2,}")
SPACE_RE = re.compile(r"[ \t\n\v\f\r]+")
MAX_INT_DIGITS = 18  # every count and index limit is far below 10^18


@dataclass(frozen=True, slots=True)
class Token:
    text: str
    line: int


_WORD_OR_NEWLINE_RE = re.compile(r"\n|[^ \t\n\v\f\r]+")


def iter_tokens(text: str) -> Iterator[Token]:
    """Tokens in file order, produced lazily so that an early error costs no full pass."""
    lineno = 1
    comment = False
    for m in _WORD_OR_NEWLINE_RE.finditer(text):
        word = m.group()
        if word == "\n":
            lineno += 1
            comment = False
            continue
        if comment:
            continue
        if word.startswith("#"):
            comment = True
            continue
        glued = _GLUED_RE.fullmatch(word) if word.endswith("}") else None
        if glued:
            yield Token(glued.group(1), lineno)
            yield Token("}", lineno)
        else:
            yield Token(word, lineno)


def tokenize(text: str) -> list[Token]:
    return list(iter_tokens(text))


class TokenStream:
    """Cursor over tokens with the typed reads the parser needs; errors name file and line."""

    def __init__(self, tokens: Iterable[Token], path: Path, last_line: int) -> None:
        self._tokens = iter(tokens)
        self._next: Token | None = next(self._tokens, None)
        self.path = path
        self._last_line = last_line

    def at_end(self) -> bool:
        return self._next is None

    def peek(self) -> Token | None:
        return self._next

    def _advance(self) -> None:
        self._next = next(self._tokens, None)

    def line(self) -> int:
        tok = self.peek()
        return tok.line if tok else self._last_line

    def error(self, message: str, line: int | None = None) -> SceneError:
        return SceneError(self.path, line if line is not None else self.line(), message)

    def fail_expected(self, what: str) -> SceneError:
        tok = self.peek()
        found = quote(tok.text) if tok else "end of file"
        return self.error(f"expected {what}, found {found}")

    def next(self, what: str) -> Token:
        tok = self.peek()
        if tok is None:
            raise self.fail_expected(what)
        self._advance()
        return tok

    def expect(self, text: str) -> Token:
        tok = self.peek()
        if tok is None or tok.text != text:
            raise self.fail_expected(f"'{text}'")
        self._advance()
        return tok

    def accept(self, text: str) -> bool:
        tok = self.peek()
        if tok is not None and tok.text == text:
            self._advance()
            return True
        return False

    def _matching(self, pattern: re.Pattern, expected: str) -> str:
        tok = self.peek()
        if tok is None or not pattern.fullmatch(tok.text):
            raise self.fail_expected(expected)
        self._advance()
        return tok.text

    def number(self, what: str) -> float:
        tok = self.peek()
        if tok is not None and _BRACES_RE.fullmatch(tok.text):
            raise self.error(f"expected a number for {what}, found {quote(tok.text)}: only one "
                             "'}' may follow a number (separate the others with spaces)")
        return float(self._matching(FLOAT_RE, f"a number for {what}"))

    def integer(self, what: str) -> int:
        tok = self.peek()
        if (tok is not None and INT_RE.fullmatch(tok.text)
                and len(tok.text.lstrip("+-").lstrip("0")) > MAX_INT_DIGITS):
            raise self.fail_expected(f"an integer of at most {MAX_INT_DIGITS} digits for {what}")
        return int(self._matching(INT_RE, f"an integer for {what}"))

    def vec3(self, what: str) -> tuple[float, float, float]:
        return (self.number(what), self.number(what), self.number(what))
