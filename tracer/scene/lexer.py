"""Tokens of the course scene format: maximal runs of non-whitespace, with line numbers.

A closing brace glued to the end of a number (`shininess 20}`) becomes its own token, as the
reference reads it. `#` starts a comment running to the end of the line: an extension (the
reference has no comment syntax) that lets our scene files say what they probe.
"""
from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

from .errors import SceneError

FLOAT_RE = re.compile(r"[+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?")
INT_RE = re.compile(r"[+-]?\d+")
_GLUED_RE = re.compile(r"(" + FLOAT_RE.pattern + r")(\}+)")


@dataclass(frozen=True)
class Token:
    text: str
    line: int


def tokenize(text: str) -> list[Token]:
    tokens: list[Token] = []
    for lineno, line in enumerate(text.splitlines(), start=1):
        for word in line.split():
            if word.startswith("#"):
                break
            glued = _GLUED_RE.fullmatch(word)
            if glued:
                tokens.append(Token(glued.group(1), lineno))
                tokens.extend(Token("}", lineno) for _ in glued.group(2))
            else:
                tokens.append(Token(word, lineno))
    return tokens


class TokenStream:
    """Cursor over tokens with the typed reads the parser needs; errors name file and line."""

    def __init__(self, tokens: list[Token], path: Path, last_line: int) -> None:
        self._tokens = tokens
        self._pos = 0
        self.path = path
        self._last_line = last_line

    def at_end(self) -> bool:
        return self._pos >= len(self._tokens)

    def peek(self) -> Token | None:
        return None if self.at_end() else self._tokens[self._pos]

    def line(self) -> int:
        tok = self.peek()
        return tok.line if tok else self._last_line

    def error(self, message: str, line: int | None = None) -> SceneError:
        return SceneError(self.path, line if line is not None else self.line(), message)

    def fail_expected(self, what: str) -> SceneError:
        tok = self.peek()
        found = f"'{tok.text}'" if tok else "end of file"
        return self.error(f"expected {what}, found {found}")

    def next(self, what: str) -> Token:
        tok = self.peek()
        if tok is None:
            raise self.fail_expected(what)
        self._pos += 1
        return tok

    def expect(self, text: str) -> Token:
        tok = self.peek()
        if tok is None or tok.text != text:
            raise self.fail_expected(f"'{text}'")
        self._pos += 1
        return tok

    def accept(self, text: str) -> bool:
        tok = self.peek()
        if tok is not None and tok.text == text:
            self._pos += 1
            return True
        return False

    def _matching(self, pattern: re.Pattern, expected: str) -> str:
        tok = self.peek()
        if tok is None or not pattern.fullmatch(tok.text):
            raise self.fail_expected(expected)
        self._pos += 1
        return tok.text

    def number(self, what: str) -> float:
        return float(self._matching(FLOAT_RE, f"a number for {what}"))

    def integer(self, what: str) -> int:
        return int(self._matching(INT_RE, f"an integer for {what}"))

    def vec3(self, what: str) -> tuple[float, float, float]:
        return (self.number(what), self.number(what), self.number(what))
