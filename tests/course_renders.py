"""The course program's own renders of every bundled scene (tests/data, see its README): the
manifest's entries, one per command line, and the keys of their images in the .npz."""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

DATA = Path(__file__).resolve().parent / "data" / "course_program_renders.npz"
MANIFEST = DATA.with_suffix(".manifest.txt")
KINDS = ("color", "normals", "depth")


@dataclass(frozen=True)
class Entry:
    scene: str  # folder/name
    width: int
    height: int
    bounces: int
    shadows: bool
    depth: tuple[float, float]
    sha256: str

    @property
    def flags(self) -> str:  # as the data's keys spell them
        return " ".join(f for f in (f"-bounces {self.bounces}" if self.bounces else "",
                                    "-shadows" if self.shadows else "") if f)

    def key(self, kind: str) -> str:
        return f"{self.scene}|{self.width}x{self.height}|{self.flags}|{kind}"


def _entry(line: str) -> Entry:
    status, scene, command, digest = line.split("\t")
    assert status == "ok", f"the course program rejected {scene}: {digest}"
    a = command.split()

    def after(flag: str, n: int = 1) -> list[str]:
        i = a.index(flag)
        return a[i + 1:i + 1 + n]

    w, h = (int(x) for x in after("-size", 2))
    lo, hi = (float(x) for x in after("-depth", 2))
    bounces = int(after("-bounces")[0]) if "-bounces" in a else 0
    return Entry(scene, w, h, bounces, "-shadows" in a, (lo, hi),
                 digest.removeprefix("sha256="))


ENTRIES = [_entry(line) for line in MANIFEST.read_text().splitlines() if line]
