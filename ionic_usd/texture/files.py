"""Texture files: PNG / ``.tx`` writing with read-back checks, and user-supplied textures.

OpenImageIO is imported inside the functions that use it.
"""

from __future__ import annotations

import os
import shutil
from collections.abc import Mapping
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Any

import numpy as np

from ionic_usd.errors import IonicError

__all__ = [
    "TextureError",
    "MAX_USER_TEXTURE_SIZE",
    "USDZ_TEXTURE_FORMATS",
    "verify_image",
    "write_maps",
    "validate_user_texture",
    "copy_user_textures",
]

MAX_USER_TEXTURE_SIZE = 16384  # pixels per side of a user texture, checked before decoding

#: OpenImageIO format names allowed inside a USDZ package, with the file extensions that
#: must go with them (USD's image plugins choose the reader by extension).
USDZ_TEXTURE_FORMATS: dict[str, tuple[str, ...]] = {
    "png": (".png",),
    "jpeg": (".jpg", ".jpeg"),
}


class TextureError(IonicError, ValueError):
    """A texture file is missing, unreadable or in a format USDZ does not allow.

    Carries the offending ``path`` and a human-readable ``problem``.
    """

    def __init__(self, path: str | os.PathLike[str], problem: str) -> None:
        self.path = Path(path)
        self.problem = problem
        super().__init__(f"texture {str(self.path)!r}: {problem}")


def _to_uint8(a: np.ndarray) -> np.ndarray:
    # round(clip(a, 0, 1) * 255) in one buffer: the same operations on the same dtype, without
    # two (n, n, 3) temporaries (np.round to 0 decimals is np.rint)
    t = np.clip(a, 0.0, 1.0)
    t *= 255.0
    np.rint(t, out=t)
    return t.astype(np.uint8)


def _write_png(buf: Any, path: Path) -> None:
    import OpenImageIO as oiio

    # zlib level 2 with the "average" filter: ~6x faster than the defaults (level 6, adaptive
    # filters); on the default temple's 9 maps 0.21 s of CPU where level 3 took 0.33 s, for
    # files 2.9 % larger (8.14 MB against 7.91; level 1: 0.18 s, 4.9 % larger).
    buf.specmod().attribute("png:compressionLevel", 2)
    buf.specmod().attribute("png:filter", 64)
    from ionic_usd.io import atomic_path

    with atomic_path(path, verify=verify_image) as tmp:
        if not buf.write(str(tmp), oiio.UINT8, "png"):
            raise TextureError(path, f"OpenImageIO could not write it: {oiio.geterror()}")


def verify_image(path: Path) -> None:
    """Check that an image file was written whole; raise :class:`TextureError` if not.

    OpenImageIO's writers can report success on a full disk and leave a truncated file. A PNG
    is checked by its own integrity data, without decoding it (~10x faster): the signature,
    then every chunk's length and CRC-32 (what a decoder checks, over every byte written) up
    to an IEND that ends the file, IHDR first and some IDAT. Other formats are decoded, every
    pixel.
    """
    if path.suffix.lower() == ".png":
        problem = _png_problem(path.read_bytes())
        if problem is not None:
            raise TextureError(path, f"written image is incomplete ({problem}); is the disk full?")
        return
    import OpenImageIO as oiio

    inp = oiio.ImageInput.open(str(path))
    if inp is None:
        raise TextureError(
            path,
            f"written image does not read back ({_one_line(oiio.geterror())}); is the disk full?",
        )
    try:
        spec = inp.spec()
        ok = inp.read_image(0, 0, 0, spec.nchannels, oiio.UINT8) is not None and not inp.has_error
    finally:
        inp.close()
    if not ok:
        raise TextureError(path, "written image is incomplete; is the disk full?")


_PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


def _png_problem(data: bytes) -> str | None:
    """What is wrong with the bytes of a PNG file as a whole (None: nothing): its signature,
    each chunk's length and CRC-32, IHDR first, an IDAT, and IEND last, at the end."""
    import zlib

    if not data.startswith(_PNG_SIGNATURE):
        return "no PNG signature"
    view = memoryview(data)
    pos, first, idat = len(_PNG_SIGNATURE), True, False
    while True:
        if pos + 12 > len(data):
            return f"it ends inside a chunk header at byte {pos:,}"
        size = int.from_bytes(view[pos : pos + 4], "big")
        end = pos + 8 + size
        if size > 0x7FFFFFFF or end + 4 > len(data):
            return f"a chunk at byte {pos:,} runs past the end of the file"
        kind = bytes(view[pos + 4 : pos + 8])
        if zlib.crc32(view[pos + 4 : end]) != int.from_bytes(view[end : end + 4], "big"):
            return f"the CRC of chunk {kind!r} at byte {pos:,} does not match"
        if first and kind != b"IHDR":
            return "the first chunk is not IHDR"
        first, idat, pos = False, idat or kind == b"IDAT", end + 4
        if kind == b"IEND":
            if pos != len(data):
                return f"{len(data) - pos:,} bytes follow IEND"
            return None if idat else "no IDAT chunk"


def _write_tx(buf: Any, path: Path) -> None:
    import OpenImageIO as oiio

    config = oiio.ImageSpec()
    config.attribute("maketx:fileformatname", "tiff")
    # maketx's default 2x2 box reduction: exact for power-of-two sizes and 2.5x faster than
    # lanczos3, with no visible difference on noise-like stone.
    config.attribute("tile_width", 64)
    config.attribute("tile_height", 64)
    config.attribute("compression", "zip")
    # No maketx:incolorspace / outcolorspace: texels are copied unconverted (colour stays
    # sRGB-encoded and tagged so; roughness and normals stay raw data).
    from ionic_usd.io import atomic_path

    with atomic_path(path, verify=verify_image) as tmp:
        if not oiio.ImageBufAlgo.make_texture(oiio.MakeTxTexture, buf, str(tmp), config):
            raise TextureError(path, f"OpenImageIO make_texture failed: {oiio.geterror()}")


def write_maps(
    folder: Path,
    prefix: str,
    planes: Mapping[str, tuple[np.ndarray, str]],
    *,
    make_tx: bool = False,
) -> dict[str, Path]:
    """Write float maps in [0, 1] as 8-bit ``<prefix>_<key>.png`` (and ``.tx``), in parallel.

    Parameters
    ----------
    folder : existing folder
    prefix : file-name prefix (the style name)
    planes : {key: ((n, n) or (n, n, 3) float array, colour space "sRGB" or "Raw")}
    make_tx : also write a mipmapped tiled ``<prefix>_<key>.tx`` of each

    Returns
    -------
    {key: png path} plus ``{key}_tx`` entries with ``make_tx``
    """
    import OpenImageIO as oiio

    def write_one(key: str) -> dict[str, Path]:
        data, colorspace = planes[key]
        buf = oiio.ImageBuf(_to_uint8(data))
        # "Raw" makes the PNG writer omit sRGB/gAMA chunks, so viewers do not re-grade data.
        buf.specmod().attribute("oiio:ColorSpace", colorspace)
        done = {key: folder / f"{prefix}_{key}.png"}
        _write_png(buf, done[key])
        if make_tx:
            done[f"{key}_tx"] = folder / f"{prefix}_{key}.tx"
            _write_tx(buf, done[f"{key}_tx"])
        return done

    # zlib and maketx run outside the GIL: the maps encode in parallel.
    with ThreadPoolExecutor(max_workers=min(len(planes), os.cpu_count() or 1)) as pool:
        results = list(pool.map(write_one, planes))
    written: dict[str, Path] = {}
    for part in results:
        written.update(part)
    return written


# ------------------------------------------------------------------------- user textures


def _one_line(message: str) -> str:
    return "; ".join(part.strip() for part in message.splitlines() if part.strip())


def validate_user_texture(path: str | os.PathLike[str]) -> Path:
    """Check that a user-supplied texture can be packaged into a USDZ.

    The file must exist, be decodable by OpenImageIO, be PNG or JPEG by its *content*, and
    carry an extension matching that content (USD picks its image reader by extension).

    Returns
    -------
    Path
        The resolved path.

    Raises
    ------
    TextureError
        Naming the path and the problem.
    """
    import OpenImageIO as oiio

    p = Path(path)
    if not p.exists():
        raise TextureError(p, "file does not exist")
    if not p.is_file():
        raise TextureError(p, "not a regular file")
    if not os.access(p, os.R_OK):
        raise TextureError(p, "file is not readable (permission denied)")
    inp = oiio.ImageInput.open(str(p))
    if inp is None:
        msg = _one_line(oiio.geterror()) or "unknown format"
        raise TextureError(p, f"OpenImageIO cannot read it as an image ({msg})")
    try:
        fmt = inp.format_name()
        spec = inp.spec()
        if fmt not in USDZ_TEXTURE_FORMATS:
            allowed = ", ".join(sorted(USDZ_TEXTURE_FORMATS))
            raise TextureError(p, f"format is {fmt!r}; USDZ allows only {allowed}")
        if p.suffix.lower() not in USDZ_TEXTURE_FORMATS[fmt]:
            raise TextureError(
                p,
                f"content is {fmt} but the extension is {p.suffix!r}; "
                f"rename it to one of {list(USDZ_TEXTURE_FORMATS[fmt])}",
            )
        if spec.width <= 0 or spec.height <= 0:
            raise TextureError(p, "image has no pixels")
        # the header's dimensions, before any pixel is decoded (a small PNG can hold 20000²)
        if max(spec.width, spec.height) > MAX_USER_TEXTURE_SIZE or spec.depth > 1:
            raise TextureError(
                p,
                f"image is {spec.width}x{spec.height}x{spec.depth} pixels; "
                f"the limit is {MAX_USER_TEXTURE_SIZE} per side, 2-D",
            )
        # Opening only parses the header; decode the pixels to catch truncated files.
        pixels = inp.read_image(0, 0, 0, spec.nchannels, oiio.UINT8)
        if pixels is None:
            msg = _one_line(inp.geterror()) or "decode failed"
            raise TextureError(p, f"pixels cannot be decoded ({msg})")
    finally:
        inp.close()
    return p.resolve()


def copy_user_textures(
    mapping: Mapping[str, str | os.PathLike[str]], folder: str | os.PathLike[str]
) -> dict[str, Path]:
    """Validate every texture, then copy them all into ``folder`` under their own file names.

    Parameters
    ----------
    mapping : Mapping[str, path]
        Role (e.g. ``"basecolor"``) to source file.
    folder : path
        Destination, created if needed; existing files of the same name are replaced
        atomically.

    Returns
    -------
    dict[str, Path]
        Role to destination path.

    Raises
    ------
    TextureError
        If any source is invalid or two different sources share a file name; nothing is
        copied in that case.
    """
    sources = {role: validate_user_texture(src) for role, src in mapping.items()}
    by_name: dict[str, Path] = {}
    for role, src in sources.items():
        other = by_name.setdefault(src.name, src)
        if other != src:
            raise TextureError(src, f"file name clashes with {str(other)!r} (role {role!r})")
    out = Path(folder)
    out.mkdir(parents=True, exist_ok=True)
    copied: dict[str, Path] = {}
    for role, src in sources.items():
        dest = out / src.name
        if not (dest.exists() and dest.samefile(src)):
            from ionic_usd.io import atomic_path

            with atomic_path(dest) as tmp:
                shutil.copyfile(src, tmp)
        copied[role] = dest
    return copied
