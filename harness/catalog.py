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

from raycheck.tracer.scene.request import RenderRequest

# scenes/ sits beside this package in the repository (harness/, scenes/) and in an installed
# wheel (raycheck/harness/, raycheck/scenes/)
REPO = Path(__file__).resolve().parent.parent
SCENES = REPO / "scenes"
DEFAULT_SIZE = (800, 800)


@dataclass(frozen=True)
class BundledScene:
    path: Path
    flags: tuple[str, ...]  # typical course flags, without -input/-output/-size/-depth
    size: tuple[int, int] | None  # a size the scene needs, if any
    depth_range: tuple[float, float] | None  # from `# flags: -depth a b`; None: not given
    description: str
    depth_origin: str = "the scene's # flags line"  # where depth_range comes from
    label: str = ""  # folder/name, unique within a run (see unique_labels); "" until given

    @property
    def name(self) -> str:
        return self.path.stem

    @property
    def id(self) -> str:
        """folder/name (course/arch) unless a run gave it a longer, unique label."""
        return self.label or f"{self.path.parent.name}/{self.path.stem}"

    def typical_request(self, size: tuple[int, int]) -> RenderRequest:
        """The scene's typical flags at `size`, with its depth range (0..1 if it has none:
        see with_depth_range); color only."""
        from raycheck.tracer.scene.flags import request_from_argv

        lo, hi = self.depth_range or (0.0, 1.0)
        request = request_from_argv(["-size", str(size[0]), str(size[1]), *self.flags])
        return replace(request, kinds=("color",), depth_min=lo, depth_max=hi)


def with_depth_range(scene: BundledScene) -> BundledScene:
    """The scene with a depth range: its own, else one from its visible hits (a 0..1 range
    would show every hit beyond 1 as white and say nothing), else 0..1 when nothing is hit."""
    if scene.depth_range is not None:
        return scene
    from .renderers import visible_depth_range

    found = visible_depth_range(scene.path)
    if found is None:
        return replace(scene, depth_range=(0.0, 1.0), depth_origin="the default (no visible hit)")
    return replace(scene, depth_range=found, depth_origin="the visible hits")


def read_header(path: Path) -> BundledScene:
    """The metadata of a scene's leading comment lines; a malformed `# flags:` or `# size:`
    line is a SceneError naming its line."""
    from raycheck.tracer.scene import SceneError
    from raycheck.tracer.scene.flags import FlagError, parse_course_flags

    flags: list[str] = []
    size = None
    depth_range = None
    description = ""
    try:
        text = Path(path).read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as e:
        raise SceneError(path, None, f"cannot read the scene: {e}") from None
    for number, line in enumerate(text.splitlines(), 1):
        text = line.strip()
        if not text:
            continue
        if not text.startswith("#"):
            break
        body = text.lstrip("#").strip()
        key, _, value = body.partition(":")
        if key == "flags":
            try:
                words = shlex.split(value)
                if "-depth" in words:  # `-depth min max` here: the file is the renderer's
                    i = words.index("-depth") + 3
                    words[i:i] = ["depth.png"]
                cmd = parse_course_flags(words, require_input=False)
            except (ValueError, FlagError) as e:
                raise SceneError(path, number, f"bad '# flags:' line: {e}") from None
            if cmd.input is not None or set(cmd.outputs) - {"depth"} or \
                    cmd.request.size != RenderRequest().size:
                raise SceneError(path, number, "bad '# flags:' line: only -bounces, -shadows, "
                                 "-jitter, -filter and -depth min max belong there")
            if "depth" in cmd.outputs:
                depth_range = cmd.request.depth_range
            flags = cmd.request.feature_flags
        elif key == "size":
            words = value.split()
            if len(words) != 2 or not all(w.isascii() and w.isdigit() and 0 < int(w) <= 16384
                                          for w in words):
                raise SceneError(path, number, f"bad '# size:' line: expected two sides in "
                                 f"1..16384, found {value.strip()!r}")
            size = (int(words[0]), int(words[1]))
        elif not description:
            description = body
    return BundledScene(path, tuple(flags), size, depth_range, description)


def unique_labels(scenes: list[BundledScene]) -> list[BundledScene]:
    """The scenes, each file once, labelled folder/name, or with as many more parent folders
    as it takes to tell apart scenes of the same name in different places (their case folders
    and matrix rows must not be shared)."""
    seen: dict[Path, BundledScene] = {}
    for scene in scenes:
        seen.setdefault(scene.path.resolve(), scene)
    parts = {path: path.with_suffix("").parts for path in seen}
    depth = dict.fromkeys(seen, 2)
    while True:
        labels = {p: "/".join(parts[p][-depth[p]:]) for p in seen}
        clashes = [p for p in seen if list(labels.values()).count(labels[p]) > 1
                   and depth[p] < len(parts[p])]
        if not clashes:
            break
        for p in clashes:
            depth[p] += 1
    return [replace(scene, label=labels[path]) for path, scene in seen.items()]


def bundled_path(name: str) -> Path | None:
    """A bundled scene named like `course/arch` (folder/name, as tables show it), or None."""
    folder, _, stem = name.partition("/")
    path = SCENES / folder / f"{stem}.txt"
    return path if stem and "/" not in stem and path.is_file() else None


def bundled(group: str) -> list[BundledScene]:
    """The scenes of scenes/<group>/, sorted by name."""
    return [read_header(p) for p in sorted((SCENES / group).glob("*.txt"))]


def all_bundled() -> list[BundledScene]:
    """The scenes a check runs when none are named: the course scenes and the probes."""
    return bundled("course") + bundled("features")


def scenes_named(paths: list[Path]) -> list[BundledScene]:
    """The scenes of a command line (scene_headers), or every bundled one where none is
    named."""
    return scene_headers(paths) or all_bundled()


def scene_headers(paths: list[Path]) -> list[BundledScene]:
    """The scenes named on a command line (files, or bundled scenes by name: course/arch),
    each parsed (bad ones fail here, with file and line, before any work) with its header."""
    from raycheck.tracer.scene import load_scene

    headers = []
    for path in paths:
        bundled = None if Path(path).exists() else bundled_path(str(path))
        path = bundled or path
        load_scene(path)
        headers.append(read_header(path))
    return headers
