"""Cube-map folders: six 8-bit RGB PNGs, texel value byte/255 with no gamma (spec §2, §7).

Faces are read as PNG only (whatever their file contents claim to be). Other PNG kinds are
accepted and converted: gray is replicated, alpha is dropped, palettes are expanded and 16-bit
samples keep their high byte (as a PNG decoder asked for 8-bit RGB gives them). A face that is
missing, not a PNG, truncated or corrupt, or over the size limits is a SceneError naming the
scene line of the `cubeMap` field.
"""
from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np

from .errors import SceneError
from .limits import MAX_CUBEMAP_FACE_BYTES, MAX_CUBEMAP_FACE_PIXELS, check_file_size
from .model import CubeMap


def _rgb8(im) -> np.ndarray:
    """(H, W, 3) uint8 of an opened PIL image."""
    if im.mode in ("I;16", "I;16B", "I;16L", "I"):  # 16-bit gray: Pillow's RGB convert clips
        gray = np.asarray(im).astype(np.int64) >> 8
        return np.repeat(np.clip(gray, 0, 255).astype(np.uint8)[..., None], 3, axis=2)
    return np.asarray(im.convert("RGB"), dtype=np.uint8)


def load_face(path: Path, ref_path: Path, ref_line: int) -> np.ndarray:
    from PIL import Image, UnidentifiedImageError

    if not path.is_file():
        raise SceneError(ref_path, ref_line, f"cube-map face not found: {path}")
    check_file_size(path, MAX_CUBEMAP_FACE_BYTES, ref_path, ref_line)
    too_large = f"cube-map face {path} has more than {MAX_CUBEMAP_FACE_PIXELS} pixels"
    try:
        with warnings.catch_warnings():
            # DecompressionBombWarning (we check the size ourselves), palette transparency notes
            warnings.simplefilter("ignore")
            with Image.open(path, formats=["PNG"]) as im:
                if im.width * im.height > MAX_CUBEMAP_FACE_PIXELS:
                    raise SceneError(ref_path, ref_line, too_large)
                if im.width < 1 or im.height < 1:
                    raise SceneError(ref_path, ref_line, f"cube-map face {path} is empty")
                rgb = _rgb8(im)
    except SceneError:
        raise
    except Image.DecompressionBombError:
        raise SceneError(ref_path, ref_line, too_large) from None
    except UnidentifiedImageError:
        raise SceneError(ref_path, ref_line, f"cube-map face {path} is not a PNG image") from None
    except MemoryError:
        raise SceneError(ref_path, ref_line,
                         f"out of memory reading cube-map face {path}") from None
    except Exception as e:  # noqa: BLE001 - Pillow's decoders raise OSError, SyntaxError,
        # ValueError, EOFError, struct.error, zlib.error ... for corrupt or truncated files
        detail = str(e).splitlines()[0] if str(e) else type(e).__name__
        raise SceneError(ref_path, ref_line,
                         f"cannot read cube-map face {path}: {detail}") from None
    return rgb.astype(np.float32) / np.float32(255.0)


def load_cube_map(folder: Path, ref_path: Path, ref_line: int) -> CubeMap:
    if not folder.is_dir():
        raise SceneError(ref_path, ref_line, f"cube-map folder not found: {folder}")
    faces = {name: load_face(folder / f"{name}.png", ref_path, ref_line)
             for name in CubeMap.FACE_NAMES}
    return CubeMap(folder=folder, faces=faces)
