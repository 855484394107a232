"""Cube-map folders: six 8-bit RGB PNGs, texel value byte/255 with no gamma (spec §2, §7).

Faces are read as PNG only (whatever their file contents claim to be). Other PNG kinds are
accepted and converted: gray is replicated, alpha is dropped, palettes are expanded and 16-bit
samples keep their high byte (as a PNG decoder asked for 8-bit RGB gives them). A face that is
missing, not a PNG, truncated or corrupt, or over the size limits is a SceneError naming the
scene line of the `cubeMap` field.

Decoding is most of a large cube map's cost (a 6x1024^2 map: ~0.2 s, against a 0.1 s render
at 200x200), and the same faces are read by every render process of a scene: large faces are
kept decoded in the per-machine cache, keyed by their bytes and the decoder.
"""
from __future__ import annotations

import hashlib
import io
import warnings
from functools import lru_cache
from pathlib import Path

import numpy as np

from .. import cache
from .errors import SceneError
from .limits import (
    BYTES_PER_TEXEL,
    MAX_CUBEMAP_FACE_BYTES,
    MAX_CUBEMAP_FACE_PIXELS,
    Budget,
    BudgetError,
    check_file_size,
)
from .model import CubeMap


def _rgb8(im) -> np.ndarray:
    """(H, W, 3) uint8 of an opened PIL image."""
    if im.mode in ("I;16", "I;16B", "I;16L", "I"):  # 16-bit gray: Pillow's RGB convert clips
        gray = np.asarray(im).astype(np.int64) >> 8
        return np.repeat(np.clip(gray, 0, 255).astype(np.uint8)[..., None], 3, axis=2)
    return np.asarray(im if im.mode == "RGB" else im.convert("RGB"), dtype=np.uint8)


# Faces of at least this many texels are kept decoded in the per-machine cache (cache.py):
# a smaller face decodes in about the time reading its entry takes (256x256: ~2 ms either way).
CACHED_FACE_TEXELS = 256 * 256


def load_face(path: Path, ref_path: Path, ref_line: int) -> np.ndarray:
    """The face's (H, W, 3) uint8 texels, from the cache where its bytes were decoded before."""
    if not path.is_file():
        raise SceneError(ref_path, ref_line, f"cube-map face not found: {path}")
    check_file_size(path, MAX_CUBEMAP_FACE_BYTES, ref_path, ref_line)
    try:
        data = path.read_bytes()
    except OSError as e:
        raise SceneError(ref_path, ref_line,
                         f"cannot read cube-map face {path}: {e.strerror or e}") from None
    too_large = f"cube-map face {path} has more than {MAX_CUBEMAP_FACE_PIXELS} pixels"
    entry = cache.cache_folder() / "faces" / f"{_cache_key(data)}.npz"
    rgb = (cache.load_arrays(entry) or {}).get("rgb8")
    if rgb is not None and rgb.dtype == np.uint8 and rgb.ndim == 3 and rgb.shape[2] == 3 \
            and rgb.size > 0:
        if rgb.shape[0] * rgb.shape[1] > MAX_CUBEMAP_FACE_PIXELS:
            raise SceneError(ref_path, ref_line, too_large)
    else:
        rgb = _decode(data, path, ref_path, ref_line, too_large)
        if rgb.shape[0] * rgb.shape[1] >= CACHED_FACE_TEXELS:
            cache.save_arrays(entry, {"rgb8": rgb}, compress=False)
    rgb.setflags(write=False)  # shared by every user of the scene (and, decoded, Pillow's)
    return rgb


@lru_cache(maxsize=1)
def _decoder_digest() -> bytes:
    """What a decode depends on besides the file: this module's rules and Pillow's version."""
    from PIL import __version__ as pillow

    return hashlib.blake2b(Path(__file__).read_bytes() + pillow.encode()).digest()


def _cache_key(data: bytes) -> str:
    return hashlib.blake2b(data, key=_decoder_digest()[:64]).hexdigest()


def _decode(data: bytes, path: Path, ref_path: Path, ref_line: int,
            too_large: str) -> np.ndarray:
    from PIL import Image, UnidentifiedImageError

    try:
        with warnings.catch_warnings():
            # DecompressionBombWarning (we check the size ourselves), palette transparency notes
            warnings.simplefilter("ignore")
            with Image.open(io.BytesIO(data), formats=["PNG"]) as im:
                if im.width * im.height > MAX_CUBEMAP_FACE_PIXELS:
                    raise SceneError(ref_path, ref_line, too_large)
                if im.width < 1 or im.height < 1:
                    raise SceneError(ref_path, ref_line, f"cube-map face {path} is empty")
                return _rgb8(im)
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


def face_texels(path: Path) -> int:
    """width x height from the PNG's header, or 0 where it has none (load_face then says
    what is wrong with the file)."""
    from PIL import Image

    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            with Image.open(path, formats=["PNG"]) as im:
                return im.width * im.height
    except Exception:  # noqa: BLE001 - any unreadable header: left to load_face's messages
        return 0


def load_cube_map(folder: Path, ref_path: Path, ref_line: int,
                  budget: Budget = Budget()) -> CubeMap:
    if not folder.is_dir():
        raise SceneError(ref_path, ref_line, f"cube-map folder not found: {folder}")
    paths = {name: folder / f"{name}.png" for name in CubeMap.FACE_NAMES}
    texels = sum(face_texels(p) for p in paths.values() if p.is_file())
    try:  # all six faces from their headers, before decoding any
        budget.check_memory(texels * BYTES_PER_TEXEL, f"the cube map {folder} ({texels} texels)")
    except BudgetError as e:
        raise SceneError(ref_path, ref_line, str(e)) from None
    return CubeMap(folder, {name: load_face(path, ref_path, ref_line)
                            for name, path in paths.items()})
