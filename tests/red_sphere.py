"""The scene the command-line tests render (the tracer's and Mitsuba's): one red sphere lit head
on by a directional light, on a blue background."""
from __future__ import annotations

from pathlib import Path

TEXT = """PerspectiveCamera { center 0 0 10 direction 0 0 -1 up 0 1 0 angle 30 }
Lights { numLights 1 DirectionalLight { direction 0 0 -1 color 1 1 1 } }
Background { color 0 0 1 }
Materials { numMaterials 1 Material { diffuseColor 1 0 0 specularColor 0.5 0.5 0.5 shininess 4 } }
Group { numObjects 1 MaterialIndex 0 Sphere { center 0 0 0 radius 2 } }
"""


def write(folder: Path) -> Path:
    path = folder / "scene.txt"
    path.write_text(TEXT)
    return path
