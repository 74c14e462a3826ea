"""Reading map images of any common depth and band count, and mapping them to 8-bit RGB.

Aerial and satellite imagery is usually a GeoTIFF of 11 or 12 significant bits stored in
uint16, often with 4 bands (blue, green, red, near infrared) that the file does not label
as colour. OpenCV's decoder keeps one band of such a file, and casting 16 bits to 8 keeps
the high byte, which turns an 11-bit scene nearly black. Here TIFFs are decoded with
tifffile (every band, every layout), other formats with OpenCV, and an image of more than
8 bits is stretched to 8 bits per band between percentiles of the values present.
"""

from __future__ import annotations

import logging
import zlib
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from curiosity_cli.errors import DatasetError
from curiosity_cli.files import display_path

#: The default stretch of images of more than 8 bits: each band's 2nd to 98th percentile
#: maps to 0..255 (the "cumulative count cut" that GIS viewers such as QGIS default to).
DEFAULT_STRETCH = (2.0, 98.0)

_TIFF_MAGIC = (b"II*\x00", b"MM\x00*", b"II+\x00", b"MM\x00+")
#: OpenCV's default limit on the pixels of a decoded image (``CV_IO_MAX_IMAGE_PIXELS``).
_MAX_PIXELS = 1 << 30
_PNG_MAGIC = b"\x89PNG\r\n\x1a\n"
#: Every PNG ends with this chunk (length 0, type IEND, its CRC).
_PNG_END = b"\x00\x00\x00\x00IEND\xaeB`\x82"


@dataclass(frozen=True)
class Raster:
    """An image as its file holds it.

    Attributes
    ----------
    pixels : (H, W, B) ndarray
        Bands last, in file order (RGB order for colour files OpenCV decodes), in the
        file's own dtype.
    colour : {"rgb", "grey", None}
        What the file says its bands are: "rgb" when its first three bands are red,
        green and blue, "grey" for a single band, None when it does not say (a
        multi-band TIFF of "minisblack" samples, as satellite products are).
    """

    pixels: np.ndarray
    colour: str | None


@dataclass(frozen=True)
class Rendering:
    """How a raster became the 8-bit RGB image the words are made from.

    Attributes
    ----------
    bands : tuple of int
        The file's bands (0-based) shown as R, G, B, or one band shown as grey.
    dtype : str
        The file's sample type, e.g. ``"uint16"``.
    low, high : tuple of float
        Per shown band, the values mapped to 0 and 255; None when 8-bit data is used as is.
    percentiles : (float, float) or None
        The percentiles ``low`` and ``high`` come from; None when used as is.
    """

    bands: tuple[int, ...]
    dtype: str
    low: tuple[float, ...] | None
    high: tuple[float, ...] | None
    percentiles: tuple[float, float] | None

    def describe(self) -> str:
        """One line: which bands, and the range each was mapped from, e.g. for ``datasets show``."""
        names = ("R", "G", "B") if len(self.bands) == 3 else ("grey",)
        shown = ", ".join(f"{n} = band {b}" for n, b in zip(names, self.bands))
        if self.low is None:
            return f"{self.dtype}, {shown}; used as is (0..255)"
        ranges = ", ".join(f"{n} {lo:g}..{hi:g}" for n, lo, hi in zip(names, self.low, self.high))
        p_low, p_high = self.percentiles
        return f"{self.dtype}, {shown}; stretched {ranges} (percentiles {p_low:g} to {p_high:g} of each band) to 0..255"


def read_raster(path: Path, where: str) -> Raster:
    """Decode an image file with all its bands and its own sample type.

    Parameters
    ----------
    path : Path
        A PNG, JPEG, TIFF (any band count, planar or interleaved, 8 to 32 bits) or any
        other format OpenCV reads.
    where : str
        Prefix of error messages: the dataset file and key that named ``path``.

    Returns
    -------
    Raster

    Raises
    ------
    DatasetError
        Empty, unreadable, or an unsupported layout; the message names the file.
    """
    path = Path(path)
    shown = display_path(path)
    if not path.is_file():
        raise DatasetError(f"{where}: {shown} is not a file; expected a PNG, JPEG or TIFF image")
    data = np.fromfile(path, dtype=np.uint8)
    if data.size == 0:
        raise DatasetError(f"{where}: {shown} is empty; expected a PNG, JPEG or TIFF image")
    if bytes(data[:4]) in _TIFF_MAGIC:
        return _read_tiff(path, shown, where)
    if bytes(data[:8]) == _PNG_MAGIC:
        damage = _png_damage(memoryview(data))
        if damage is not None:
            raise DatasetError(f"{where}: {shown} {damage}")
    import cv2

    # imdecode over bytes rather than imread: a path with any characters works
    try:
        pixels = cv2.imdecode(data, cv2.IMREAD_UNCHANGED)
    except cv2.error as exc:  # e.g. a header declaring more pixels than OpenCV will allocate
        raise DatasetError(
            f"{where}: cannot decode {shown} (OpenCV: {exc.err}); expected a PNG, JPEG or TIFF image "
            f"of at most {_MAX_PIXELS:,} pixels"
        ) from None
    if pixels is None or pixels.size == 0:
        raise DatasetError(f"{where}: cannot read {shown}; expected a PNG, JPEG or TIFF image")
    if pixels.ndim == 2:
        return Raster(pixels[:, :, None], "grey")
    if pixels.shape[2] in (3, 4):
        # OpenCV decodes BGR(A); the package speaks RGB. Alpha is kept as a 4th band.
        order = [2, 1, 0] + ([3] if pixels.shape[2] == 4 else [])
        return Raster(np.ascontiguousarray(pixels[:, :, order]), "rgb")
    return Raster(pixels, None)


def _png_damage(data: memoryview) -> str | None:
    """Why libpng would refuse a PNG file's bytes, in words, or None.

    Checked here because libpng prints its own line on stderr beside our error: a file
    cut short, or a critical chunk (``IHDR``, ``PLTE``, ``IDAT``, ``IEND``, those with an
    upper-case first letter) whose CRC does not match its bytes. libpng only warns of an
    ancillary chunk's, and skips it; so does this.
    """
    if bytes(data[-12:]) != _PNG_END:
        return "is truncated (no IEND chunk at its end); expected a whole PNG image"
    at = len(_PNG_MAGIC)
    while at + 12 <= len(data):  # length, type, data, CRC
        length, kind = int.from_bytes(data[at : at + 4], "big"), bytes(data[at + 4 : at + 8])
        end = at + 8 + length
        if end + 4 > len(data):
            break
        if kind[:1].isupper() and zlib.crc32(data[at + 4 : end]) != int.from_bytes(data[end : end + 4], "big"):
            name = kind.decode("ascii", "replace")
            return f"is corrupt (its {name} chunk at byte {at} fails its CRC check); expected an intact PNG image"
        if kind == b"IEND":
            return None
        at = end + 4
    return f"is corrupt (its chunks do not add up to the file, from byte {at}); expected an intact PNG image"


def decode_tiff(data: bytes, shown: str, where: str) -> Raster:
    """A TIFF file's bytes as a :class:`Raster`; ``shown`` names it in errors."""
    import io

    return _read_tiff(io.BytesIO(data), shown, where)


def _read_tiff(source, shown: str, where: str) -> Raster:
    import tifffile

    # tifffile logs GeoTIFF and other private tags it does not know as warnings: noise
    # for a user whose file is fine.
    logger = logging.getLogger("tifffile")
    level = logger.level
    logger.setLevel(logging.ERROR)
    try:
        with tifffile.TiffFile(source) as tif:
            page = tif.pages.first
            # Reduced-resolution overviews are fine; more images of the full size would be
            # bands (or times) stored as pages, and reading only the first would be wrong.
            same_size = sum(1 for p in tif.pages if p.shape == page.shape)
            photometric = int(page.photometric)
            pixels = page.asarray()
            samples = page.samplesperpixel
            planar = int(page.planarconfig) == 2
    except Exception as exc:  # tifffile raises many types for a broken file
        raise DatasetError(f"{where}: cannot read {shown} as TIFF ({type(exc).__name__}); expected a valid TIFF image") from None
    finally:
        logger.setLevel(level)
    if same_size > 1:
        rows, cols = (pixels.shape[1:3] if planar and pixels.ndim == 3 else pixels.shape[:2])
        raise DatasetError(
            f"{where}: {shown} holds {same_size} images of {rows} x {cols} px; expected one image with its bands as samples"
        )
    if pixels.ndim == 3 and samples > 1 and planar:
        pixels = np.moveaxis(pixels, 0, -1)
    if pixels.ndim == 2:
        pixels = pixels[:, :, None]
    if pixels.ndim != 3 or pixels.shape[2] != samples:
        raise DatasetError(
            f"{where}: {shown} holds an array of shape {pixels.shape}; expected one image of rows x cols x bands"
        )
    if pixels.dtype.kind not in "uif" or pixels.dtype.itemsize > 8:
        raise DatasetError(f"{where}: {shown} has {pixels.dtype} samples; expected integer or floating-point bands")
    # TIFF photometric interpretation: 0, 1 grey (white or black is zero), 2 RGB, 3 palette.
    if photometric == 3:
        raise DatasetError(f"{where}: {shown} is a palette (indexed colour) TIFF; expected grey, RGB or multi-band samples")
    if photometric == 0:
        pixels = _invert(pixels)
    if photometric == 2 and samples >= 3:
        colour = "rgb"
    elif samples == 1 and photometric in (0, 1):
        colour = "grey"
    else:
        colour = None
    return Raster(np.ascontiguousarray(pixels), colour)


def _invert(pixels: np.ndarray) -> np.ndarray:
    """A "white is zero" image as "black is zero"."""
    if pixels.dtype.kind == "f":
        return pixels.max() - pixels
    return np.iinfo(pixels.dtype).max - pixels


def render_rgb(
    raster: Raster,
    bands: tuple[int, ...] | None,
    stretch: tuple[float, float],
    where: str,
) -> tuple[np.ndarray, Rendering]:
    """The 8-bit RGB image the words are made from.

    Parameters
    ----------
    raster : Raster
    bands : tuple of int or None
        The file's bands (0-based) to show as R, G, B, or a single band to show as grey.
        None: the file's own interpretation (RGB, or grey for one band).
    stretch : (float, float)
        Percentiles ``(low, high)``, ``0 <= low < high <= 100``: for data of more than 8
        bits, each shown band's ``low``-th percentile maps to 0 and its ``high``-th to 255,
        linearly, clipped outside. 8-bit data is used as is.
    where : str
        Prefix of error messages: the dataset file.

    Returns
    -------
    image : (H, W, 3) uint8 ndarray
        RGB; the three channels are equal for a grey image.
    rendering : Rendering

    Raises
    ------
    DatasetError
        ``bands`` missing where the file does not say which bands are colour, or naming
        a band the file does not have.
    """
    pixels = raster.pixels
    count = pixels.shape[2]
    if bands is None:
        if raster.colour == "rgb":
            bands = (0, 1, 2)
        elif raster.colour == "grey":
            bands = (0,)
        else:
            raise DatasetError(
                f"{where}: bands: the image has {count} bands and does not say which are red, green "
                "and blue; expected bands: [r, g, b] (0-based band indices, e.g. [2, 1, 0] for B, G, R, NIR) "
                "or [k] for one grey band"
            )
    if len(bands) not in (1, 3) or any(not 0 <= b < count for b in bands):
        raise DatasetError(
            f"{where}: bands: got {list(bands)}, expected 3 band indices (or 1 for grey) in 0..{count - 1}"
        )
    chosen = pixels[:, :, list(bands)]
    if chosen.dtype == np.uint8:
        rendering = Rendering(tuple(bands), str(pixels.dtype), None, None, None)
        out = chosen
    else:
        values = chosen.astype(np.float64)
        if chosen.dtype.kind == "f":
            # NaN and infinities mark no-data in floating-point products: left out of the
            # percentiles, shown black.
            values[~np.isfinite(values)] = np.nan
            if np.isnan(values).all(axis=(0, 1)).any():
                raise DatasetError(f"{where}: image: a shown band holds no finite value; expected image data")
            low = np.nanpercentile(values, stretch[0], axis=(0, 1))
            high = np.nanpercentile(values, stretch[1], axis=(0, 1))
        else:
            low = np.percentile(values, stretch[0], axis=(0, 1))
            high = np.percentile(values, stretch[1], axis=(0, 1))
        # A band with one value everywhere has no range to stretch: it maps to 0.
        span = np.where(high > low, high - low, 1.0)
        scaled = np.nan_to_num(np.floor((values - low) / span * 255.0 + 0.5), nan=0.0)
        out = np.clip(scaled, 0, 255).astype(np.uint8)
        rendering = Rendering(
            tuple(bands), str(pixels.dtype), tuple(low.tolist()), tuple(high.tolist()), tuple(stretch)
        )
    if out.shape[2] == 1:
        out = np.repeat(out, 3, axis=2)
    return np.ascontiguousarray(out), rendering
