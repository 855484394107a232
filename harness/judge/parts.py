"""The reference's parts of a case's color image: the tracer's auxiliary images
(raycheck.tracer.shade.auxiliary) with what the findings need to read them."""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from raycheck.tracer.scene.model import Scene
from raycheck.tracer.shade.auxiliary import SceneObjectInfo

from ..cases import Case


@dataclass(frozen=True)
class Parts:
    """One primary ray per pixel of the case (without -jitter and -filter): the images of
    auxiliary.py by name, the color image they add up to, and the scene's objects."""

    images: dict[str, np.ndarray]
    color: np.ndarray  # (h, w, 3) float32
    objects: list[SceneObjectInfo]
    scene: Scene

    @property
    def hit(self) -> np.ndarray:
        return self.images["object"] >= 0

    def dull(self) -> np.ndarray:
        """Pixels without a highlight of their own: every light's specular term under a
        level."""
        return np.asarray((self.images["specular"] < 1.0 / 255.0).all(axis=(2, 3)))

    def unshadowed(self) -> np.ndarray:
        """Pixels whose primary ray hits no mirror and none of whose shadow rays is blocked:
        where shadows cannot darken a correct image (a mirror shows other points' shadows)."""
        return self.hit & (self.images["mirror_depth"] == 0) & \
            ~self.images["shadow"].astype(bool).any(axis=2)


def reference_parts(case: Case) -> Parts | None:
    """The course-mode tracer's parts of the case's color image (one ray a pixel: without
    -jitter and -filter); None where the scene cannot be rendered."""
    from raycheck.tracer.options import RenderOptions
    from raycheck.tracer.render import render
    from raycheck.tracer.scene import SceneError, load_scene
    from raycheck.tracer.scene.request import request_fields
    from raycheck.tracer.shade.auxiliary import AUX_KINDS, scene_objects

    request = replace(case.request, jitter=False, filter=False, kinds=("color",))
    try:
        scene = load_scene(case.scene.path)
        result = render(scene, RenderOptions(**request_fields(request), aux=AUX_KINDS))
    except (SceneError, ValueError, OSError, RuntimeError, MemoryError):  # Dr.Jit's too
        return None
    assert result.color is not None  # the request asks for it
    return Parts(result.aux, result.color, scene_objects(scene), scene)
