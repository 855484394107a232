"""Cube-map folders: six 8-bit RGB PNGs, texel value byte/255 with no gamma (spec §2, §7)."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from .errors import SceneError
from .limits import MAX_CUBEMAP_FACE_PIXELS
from .model import CubeMap


def load_face(path: Path, ref_path: Path, ref_line: int) -> np.ndarray:
    from PIL import Image, UnidentifiedImageError

    if not path.is_file():
        raise SceneError(ref_path, ref_line, f"cube-map face not found: {path}")
    try:
        with Image.open(path) as im:
            if im.width * im.height > MAX_CUBEMAP_FACE_PIXELS:
                raise SceneError(ref_path, ref_line,
                                 f"cube-map face {path} is {im.width}x{im.height}, too large")
            rgb = np.asarray(im.convert("RGB"), dtype=np.uint8)
    except (UnidentifiedImageError, OSError, ValueError) as e:
        raise SceneError(ref_path, ref_line, f"cannot read cube-map face {path}: {e}") from None
    return rgb.astype(np.float32) / np.float32(255.0)


def load_cube_map(folder: Path, ref_path: Path, ref_line: int) -> CubeMap:
    if not folder.is_dir():
        raise SceneError(ref_path, ref_line, f"cube-map folder not found: {folder}")
    faces = {name: load_face(folder / f"{name}.png", ref_path, ref_line)
             for name in CubeMap.FACE_NAMES}
    return CubeMap(folder=folder, faces=faces)
