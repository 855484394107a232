"""Writing a command's output files all or nothing (the course command line's contract: no
half-written output files), as PNG (the course's 8-bit output, quantised by each renderer's
own code) or OpenEXR (the float values as rendered). Shared by both renderers' command lines:
this is file plumbing, not image output."""
from __future__ import annotations

import os
import tempfile
from pathlib import Path
from typing import Callable, Mapping

import numpy as np

MISS = 1e30  # a depth value this large comes from a missed ray's t = FLT_MAX


def write_all(files: list[tuple[Path, Callable[[str], None]]]) -> None:
    """Write several files all or nothing: each through a temporary file in its own folder,
    and only when every one is complete are they renamed to their names. A failed or
    interrupted write leaves no half-written file and no new file at all, and every existing
    file under those names untouched. (A rename itself can only fail for reasons the command
    line checks beforehand, such as a name that is a folder.)"""
    staged: list[tuple[str, Path]] = []
    umask = os.umask(0)
    os.umask(umask)
    try:
        for path, write in files:
            path = Path(path)
            folder = path.parent if str(path.parent) else Path(".")
            try:
                fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".part", dir=folder)
                os.close(fd)
                staged.append((tmp, path))
                write(tmp)
                os.chmod(tmp, 0o666 & ~umask)  # mkstemp makes it 0600; give it open()'s mode
            except OSError as e:  # name the file asked for, not the temporary one
                raise OSError(e.errno, e.strerror or str(e), str(path)) from None
        while staged:
            tmp, path = staged[0]
            os.replace(tmp, path)
            staged.pop(0)
    finally:
        for tmp, _ in staged:
            try:
                os.unlink(tmp)
            except OSError:
                pass


def exr_writer(image: np.ndarray, kind: str) -> Callable[[str], None]:
    """An OpenEXR file of float32 values, row 0 at the top: RGB for color and normals, one Y
    channel for depth, where a missed ray (t = FLT_MAX in the course) is written as +inf."""
    import OpenEXR

    values = np.asarray(image, np.float32)
    if kind == "depth":
        with np.errstate(invalid="ignore"):
            values = np.where(values >= MISS, np.float32(np.inf), values)
    channels = {"Y" if values.ndim == 2 else "RGB": np.ascontiguousarray(values)}
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}

    def save(tmp: str) -> None:
        with OpenEXR.File(header, channels) as f:
            f.write(tmp)

    return save


def npy_writer(image: np.ndarray) -> Callable[[str], None]:
    def save(tmp: str) -> None:
        with open(tmp, "wb") as f:
            np.save(f, image)

    return save


def write_images(outputs: Mapping[str, Path], images: Mapping[str, np.ndarray],
                 png_writer: Callable[[np.ndarray], Callable[[str], None]],
                 floats: bool) -> None:
    """Each named image (kind -> file) as PNG through the renderer's own png_writer, or as
    OpenEXR for a .exr name; with floats also its values as .npy beside it. All or nothing."""
    files = []
    for kind, path in outputs.items():
        image = images[kind]
        exr = Path(path).suffix.lower() == ".exr"
        files.append((path, exr_writer(image, kind) if exr else png_writer(image)))
        if floats:
            files.append((Path(path).with_suffix(".npy"), npy_writer(image)))
    write_all(files)
