"""Writing a command's output files all or nothing (the course command line's contract: no
half-written output files), as PNG (the course's 8-bit output, quantised by each renderer's
own code) or OpenEXR (the float values as rendered). Shared by both renderers' command lines:
this is file plumbing, not image output."""
from __future__ import annotations

import os
import struct
import tempfile
import threading
import zlib
from contextlib import contextmanager
from pathlib import Path
from typing import Callable, Iterator, Mapping

import numpy as np

from ..process import current_umask, raise_swallowed, signals_deferred

MISS = 1e30  # a depth value this large comes from a missed ray's t = FLT_MAX


def write_all(files: list[tuple[Path, Callable[[str], None]]]) -> None:
    """Write several files all or nothing: each through a temporary file in its own folder,
    and only when every one is complete are they renamed to their names. A failed or
    interrupted write leaves no half-written file and no new file at all, and every existing
    file under those names untouched. (A rename itself can only fail for reasons the command
    line checks beforehand, such as a name that is a folder.) The files are written at the
    same time, one thread each: PNG encoding is most of the work, and zlib and numpy release
    the GIL while they run."""
    staged: list[tuple[str, Path]] = []
    umask = current_umask()
    try:
        for path, _ in files:
            path = Path(path)
            folder = path.parent if str(path.parent) else Path(".")
            with _named(path), signals_deferred():  # each made file is in `staged`
                fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".part", dir=folder)
                os.close(fd)
                staged.append((tmp, path))

        def write(k: int) -> None:
            (tmp, path), (_, save) = staged[k], files[k]
            with _named(path):
                save(tmp)
                os.chmod(tmp, 0o666 & ~umask)  # mkstemp makes it 0600; give it open()'s mode

        _in_threads(write, len(staged))
        raise_swallowed()
        with signals_deferred():  # Ctrl-C here would leave some files new and some old
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


@contextmanager
def _named(path: Path) -> Iterator[None]:
    """An OSError inside names the file asked for, not the temporary one."""
    try:
        yield
    except OSError as e:
        raise OSError(e.errno, e.strerror or str(e), str(path)) from None


def _in_threads(job: Callable[[int], None], n: int) -> None:
    """job(0) .. job(n-1), each in a thread of its own (job(0) in this one); every job ends
    before this returns, and then the first exception, in job order, is raised."""
    errors: list[BaseException | None] = [None] * n

    def run(k: int) -> None:
        try:
            job(k)
        except BaseException as e:  # noqa: BLE001 - handed to the caller below
            errors[k] = e

    threads = [threading.Thread(target=run, args=(k,), daemon=True) for k in range(1, n)]
    try:
        # an interrupt while a thread starts would leave it running unjoined, to write its
        # file after the caller removed it: raised once every thread is running
        with signals_deferred():
            for t in threads:
                t.start()
        if n:
            run(0)
    finally:
        for t in threads:  # every writer ends before the caller removes its files
            while t.is_alive():
                try:
                    t.join()
                except KeyboardInterrupt:
                    errors[0] = errors[0] or KeyboardInterrupt()
    for e in errors:
        if e is not None:
            raise e


def write_png_rgb8(path: str, rgb: np.ndarray) -> None:
    """(h, w, 3) uint8 pixels (row 0 = top) as an 8-bit RGB PNG: every row with the Sub
    filter, zlib level 1. Measured on twelve 800x800 course renders (docs/performance.md):
    0.48x the encoding time of Pillow's level 1 (adaptive filters) for files 1.02x as large,
    and no Pillow import (~15 ms of a render's start-up)."""
    h, w, _ = rgb.shape
    flat = np.ascontiguousarray(rgb, dtype=np.uint8).reshape(h, 3 * w)
    rows = np.empty((h, 1 + 3 * w), np.uint8)
    rows[:, 0] = 1  # filter type Sub: each byte minus the same channel a pixel before, mod 256
    rows[:, 1:4] = flat[:, :3]
    np.subtract(flat[:, 3:], flat[:, :-3], out=rows[:, 4:])
    header = struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0)  # 8-bit RGB, no interlace
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + _chunk(b"IHDR", header)
                + _chunk(b"IDAT", zlib.compress(rows.data, 1)) + _chunk(b"IEND", b""))


def _chunk(kind: bytes, data: bytes) -> bytes:
    return (struct.pack(">I", len(data)) + kind + data
            + struct.pack(">I", zlib.crc32(kind + data)))


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


def float_file(path: Path) -> Path:
    """Where --float writes an image's values: beside it, as .npy."""
    return Path(path).with_suffix(".npy")


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
            files.append((float_file(path), npy_writer(image)))
    write_all(files)
