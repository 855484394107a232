"""The one error type for bad scene input: it carries the file and line it is about."""
from __future__ import annotations

from pathlib import Path

QUOTE_LIMIT = 40  # characters of a bad token shown in a message


def printable(text: str) -> str:
    """text with every non-printable character (newlines, tabs, NUL, escape sequences, line
    separators, lone surrogates) written as a Python escape, so that a message is always one
    harmless line on a terminal. Printable text (backslashes included) is unchanged."""
    if text.isprintable():
        return text
    out = []
    for ch in text:
        if ch.isprintable():
            out.append(ch)
        else:
            out.append(ascii(ch)[1:-1] if ch != "\\" else ch)
    return "".join(out)


def quote(text: str, limit: int | None = QUOTE_LIMIT) -> str:
    """'text' for a message: escaped as by printable() and cut after `limit` characters (file
    names are given in full: limit None)."""
    if limit is not None and len(text) > limit:
        return f"'{printable(text[:limit])}...' ({len(text)} characters)"
    return f"'{printable(text)}'"


class SceneError(Exception):
    """A problem with a scene, OBJ or cube-map file; str() is 'path:line: message', one line."""

    def __init__(self, path: Path | str, line: int | None, message: str) -> None:
        self.path = Path(path)
        self.line = line
        self.message = message
        where = f"{self.path}:{line}" if line else f"{self.path}"
        super().__init__(printable(f"{where}: {message}"))
