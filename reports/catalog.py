"""The bundled scenes and the course flags each one is meant to be rendered with.

A bundled scene states its typical flags in header comments (our `#` extension):
    # flags: -bounces 4 -shadows -depth 8 18
    # size: 37 20
`-depth` there gives only the range; whoever renders the scene names the file.
"""
from __future__ import annotations

import shlex
from dataclasses import dataclass, replace
from pathlib import Path

from tracer.scene.request import RenderRequest

REPO = Path(__file__).resolve().parent.parent
SCENES = REPO / "scenes"
DEFAULT_SIZE = (800, 800)


@dataclass(frozen=True)
class BundledScene:
    path: Path
    flags: tuple[str, ...]  # typical course flags, without -input/-output/-size/-depth
    size: tuple[int, int] | None  # a size the scene needs, if any
    depth_range: tuple[float, float]
    description: str

    @property
    def name(self) -> str:
        return self.path.stem

    def typical_request(self, size: tuple[int, int]) -> RenderRequest:
        """The scene's typical flags at `size`, with its depth range; color only."""
        lo, hi = self.depth_range
        request = RenderRequest.from_argv(["-size", str(size[0]), str(size[1]), *self.flags])
        return replace(request, kinds=("color",), depth_min=lo, depth_max=hi)


def read_header(path: Path) -> BundledScene:
    flags: list[str] = []
    size = None
    depth_range = (0.0, 1.0)
    description = ""
    for line in path.read_text(encoding="utf-8").splitlines():
        text = line.strip()
        if not text:
            continue
        if not text.startswith("#"):
            break
        body = text.lstrip("#").strip()
        key, _, value = body.partition(":")
        if key == "flags":
            flags = shlex.split(value)
            if "-depth" in flags:
                i = flags.index("-depth")
                depth_range = (float(flags[i + 1]), float(flags[i + 2]))
                del flags[i:i + 3]
        elif key == "size":
            w, h = value.split()
            size = (int(w), int(h))
        elif not description:
            description = body
    return BundledScene(path, tuple(flags), size, depth_range, description)


def bundled(group: str) -> list[BundledScene]:
    """The scenes of scenes/<group>/, sorted by name."""
    return [read_header(p) for p in sorted((SCENES / group).glob("*.txt"))]
