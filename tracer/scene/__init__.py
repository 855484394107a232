"""Course scene description: the parser and the plain data both renderers read."""
from .errors import SceneError
from .model import (
    Background,
    Camera,
    CubeMap,
    DirectionalLight,
    Group,
    Material,
    Mesh,
    Plane,
    PointLight,
    Scene,
    Sphere,
    Transform,
    Triangle,
)
from .parser import load_scene, parse_scene_text

__all__ = [
    "Background", "Camera", "CubeMap", "DirectionalLight", "Group", "Material", "Mesh", "Plane",
    "PointLight", "Scene", "SceneError", "Sphere", "Transform", "Triangle", "load_scene",
    "parse_scene_text",
]
