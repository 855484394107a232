"""The one error type for bad scene input: it carries the file and line it is about."""
from __future__ import annotations

from pathlib import Path


class SceneError(Exception):
    """A problem with a scene, OBJ or cube-map file; str() is 'path:line: message'."""

    def __init__(self, path: Path | str, line: int | None, message: str) -> None:
        self.path = Path(path)
        self.line = line
        self.message = message
        where = f"{self.path}:{line}" if line else f"{self.path}"
        super().__init__(f"{where}: {message}")
