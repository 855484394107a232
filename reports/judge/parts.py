"""The reference's parts of a case's color image: the tracer's auxiliary images
(raycheck.tracer.auxiliary) with what the findings need to read them."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from raycheck.tracer.auxiliary import SceneObjectInfo
from raycheck.tracer.scene.model import Scene


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

    def lit(self, name: str) -> np.ndarray:
        """A per-light term summed over the lights whose shadow ray is not blocked."""
        unblocked = ~self.images["shadow"].astype(bool)
        return (self.images[name] * unblocked[..., None]).sum(axis=2, dtype=np.float32)
