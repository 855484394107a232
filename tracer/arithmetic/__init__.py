"""A render's arithmetic, chosen once from its mode: the parts (intersector, shader, background,
camera frame) that compute the course's way or robust mode's, and the few settings of the ray
setup that follow from them. The parts share one interface, the course's classes; robust.py's
subclasses override what robust mode computes differently."""
from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Callable

from ..accel.intersect import Intersector
from ..kernel.vecmath import normalize, normalize_safe
from ..options import Mode, RenderOptions
from ..scene.model import Camera, Scene
from ..shade.background import Background
from ..shade.camera import CameraFrame, camera_frame
from ..shade.shading import Shader
from .camera_relative import camera_relative
from .mistaken import mistaken_parts, switches_of
from .robust import RobustBackground, RobustIntersector, RobustShader, robust_camera_frame


@dataclass(frozen=True)
class Arithmetic:
    mode: Mode
    intersector: type[Intersector]
    shader: type[Shader]
    background: type[Background]
    camera_frame: Callable[[Camera], CameraFrame]
    unit: Callable  # normalisation of camera ray directions
    prepare: Callable[[Scene], Scene]  # the scene as the kernel sees it
    # the course's intersection setup: transformed meshes entered as the course enters them
    # (spec §5), camera rays answered by screen tiles of the course's triangle test
    course_tests: bool
    # ndc of a single column or row is 0 (the image's centre line), not the course's 0/0
    centred_single_lines: bool


COURSE = Arithmetic(Mode.COURSE, Intersector, Shader, Background, camera_frame, normalize,
                    prepare=lambda scene: scene, course_tests=True, centred_single_lines=False)
ROBUST = Arithmetic(Mode.ROBUST, RobustIntersector, RobustShader, RobustBackground,
                    robust_camera_frame, normalize_safe, prepare=camera_relative,
                    course_tests=False, centred_single_lines=True)
ARITHMETIC = {a.mode: a for a in (COURSE, ROBUST)}


def arithmetic(opts: RenderOptions) -> Arithmetic:
    """The arithmetic of a render: its mode's, with its mistakes switched on (course mode
    only: RenderOptions checks)."""
    if not opts.mistakes and not opts.mistake_kernel:
        return ARITHMETIC[opts.mode]
    parts = mistaken_parts(switches_of(opts))
    return replace(COURSE, intersector=parts.intersector, shader=parts.shader)
