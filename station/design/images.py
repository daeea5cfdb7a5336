"""Safe loading of mood-board and artwork images (PNG / JPEG) as sRGB arrays.

Guards, in order: the file exists and is at most :data:`MAX_FILE_BYTES`; Pillow identifies it as PNG
or JPEG; its declared size is at most :data:`MAX_PIXELS` *before* any pixel is decoded; Pillow's own
decompression-bomb check (``Image.MAX_IMAGE_PIXELS``, raised as ``DecompressionBombError`` or warned
as ``DecompressionBombWarning``) is turned into :class:`~station.design.errors.ImageLoadError`, and so is
every other failure to decode (a compressed text chunk beyond ``PngImagePlugin.MAX_TEXT_CHUNK``, a
broken chunk table): the service answers 422 naming ``image``, the CLI one line and exit status 2.

Colour: an embedded ICC profile is honoured — pixels are converted to sRGB with Pillow's ImageCms
(perceptual intent) and the result states it; an image without a profile is *assumed* sRGB and the
result says so. CMYK, greyscale, palette and alpha images are converted to RGB (alpha dropped).
"""

from __future__ import annotations

import io
import struct
import warnings
import zlib
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray
from PIL import Image, ImageCms, UnidentifiedImageError

from station.design.errors import ImageLoadError

#: Largest accepted file (bytes).
MAX_FILE_BYTES = 64 * 1024 * 1024
#: Largest accepted image (pixels, width × height): 40 megapixels.
MAX_PIXELS = 40_000_000
FORMATS = ("PNG", "JPEG")


@dataclass(frozen=True, eq=False)
class LoadedImage:
    """An image as sRGB-encoded floats in [0, 1], ``(H, W, 3)``, and how its colour was interpreted."""

    pixels: NDArray[np.float64]
    source_format: str
    colour_note: str
    profile_converted: bool


def _to_srgb(im: Image.Image) -> tuple[Image.Image, str, bool]:
    icc = im.info.get("icc_profile")
    if icc:
        try:
            src = ImageCms.ImageCmsProfile(io.BytesIO(icc))
            desc = ImageCms.getProfileDescription(src).strip() or "embedded profile"
            mode = "RGB"
            if im.mode not in ("RGB", "CMYK", "L"):
                im = im.convert("RGB")
            out = ImageCms.profileToProfile(
                im,
                src,
                ImageCms.createProfile("sRGB"),
                renderingIntent=ImageCms.Intent.PERCEPTUAL,
                outputMode=mode,
            )
            if out is None:  # pragma: no cover - only when inPlace=True
                raise ImageLoadError("image", "a convertible colour profile", desc)
            return out, f"converted from ICC profile '{desc}' to sRGB", True
        except (ImageCms.PyCMSError, OSError) as exc:
            raise ImageLoadError("image", "a valid embedded ICC profile", None, str(exc)) from exc
    out = im if im.mode == "RGB" else im.convert("RGB")  # read while *im* is open: no copy needed
    return out, "no embedded profile: assumed sRGB", False


@dataclass(frozen=True, eq=False)
class EncodedImage:
    """An image as its sRGB *encoding*, ``(H, W, 3)`` ``uint8`` (``uint16`` for 16-bit greyscale PNG).

    3 bytes a pixel (6 for 16-bit), an eighth of :class:`LoadedImage`'s float64: the service keeps
    uploads in this form and converts only the few pixels an eyedropper reads
    (``station.design.moodboard`` reads integer images as ``value / full scale``).
    """

    pixels: NDArray[np.uint8] | NDArray[np.uint16]
    source_format: str
    colour_note: str
    profile_converted: bool

    @property
    def full_scale(self) -> float:
        """The code value of white: 255 for 8-bit, 65535 for 16-bit pixels."""
        return float(np.iinfo(self.pixels.dtype).max)

    def to_float(self) -> LoadedImage:
        """The same image as float64 in [0, 1] (8 × the memory; for small images)."""
        return LoadedImage(
            self.pixels.astype(np.float64) / self.full_scale,
            self.source_format,
            self.colour_note,
            self.profile_converted,
        )


def _decode(source: Path | io.BytesIO, suffix: str, max_pixels: int) -> EncodedImage:
    """Identify, check the declared size (before decoding), decode and convert to sRGB."""
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error", Image.DecompressionBombWarning)
            with Image.open(source) as im:
                if im.format not in FORMATS:
                    raise ImageLoadError("image", "PNG or JPEG", im.format)
                w, h = im.size
                if w * h > max_pixels:
                    raise ImageLoadError("image", f"at most {max_pixels} pixels", f"{w}x{h}")
                im.load()
                fmt = str(im.format)
                if im.mode in ("I;16", "I;16B", "I;16L", "I") and not im.info.get("icc_profile"):
                    grey = np.clip(np.asarray(im), 0, 65535).astype(np.uint16)
                    return EncodedImage(
                        np.repeat(grey[..., None], 3, axis=-1),
                        fmt,
                        "16-bit greyscale, no profile: assumed sRGB",
                        False,
                    )
                converted, note, did = _to_srgb(im)
                pixels = np.asarray(converted, dtype=np.uint8)
                converted.close()
    except ImageLoadError:
        raise  # an InputError is a ValueError too: ours, raised above, passes unchanged
    except (Image.DecompressionBombError, Image.DecompressionBombWarning) as exc:
        raise ImageLoadError("image", "not a decompression bomb", None, str(exc)) from exc
    except UnidentifiedImageError as exc:
        raise ImageLoadError("image", "PNG or JPEG", suffix, str(exc)) from exc
    except OSError as exc:
        raise ImageLoadError("image", "a complete, readable image file", None, str(exc)) from exc
    except (ValueError, SyntaxError, EOFError, IndexError, struct.error, zlib.error) as exc:
        # Pillow's other decoding failures: e.g. ValueError "Decompressed data too large" for a
        # compressed text chunk (zTXt/iTXt/iCCP) beyond PngImagePlugin.MAX_TEXT_CHUNK, SyntaxError
        # "broken PNG file", a truncated chunk table
        raise ImageLoadError(
            "image", "an image whose chunks decode within Pillow's limits", None, _reason(exc)
        ) from exc
    return EncodedImage(pixels, fmt, note, did)


def _reason(exc: BaseException) -> str:
    """One line saying why Pillow refused the file (at most 200 characters)."""
    return f"{type(exc).__name__}: {' '.join(str(exc).split())}"[:200]


def decode_image(data: bytes, max_pixels: int = MAX_PIXELS, max_bytes: int = MAX_FILE_BYTES) -> EncodedImage:
    """Decode an uploaded PNG or JPEG (bytes, never written to disk) as 8-bit sRGB, the guards of
    :func:`load_image` included: the header's width × height is refused above *max_pixels* before a
    pixel is decoded, so the memory a call may take is bounded by about 10 bytes × *max_pixels* at
    the peak (Pillow's 4-byte RGB buffer, its 3-byte export and the 3-byte array), 3 bytes after.

    Raises
    ------
    ImageLoadError
        Empty or too many bytes, not PNG/JPEG, too many pixels, a bomb, a corrupt file or profile.
    """
    if not data:
        raise ImageLoadError("image", "a PNG or JPEG file as the request body", "an empty body")
    if len(data) > max_bytes:
        raise ImageLoadError("image", f"a file of at most {max_bytes} bytes", len(data))
    return _decode(io.BytesIO(data), "", max_pixels)


def load_image(
    path: str | Path, max_pixels: int = MAX_PIXELS, max_bytes: int = MAX_FILE_BYTES
) -> LoadedImage:
    """Load a PNG or JPEG file safely as sRGB (module docstring lists the guards).

    Returns
    -------
    LoadedImage
        ``pixels`` in [0, 1] (8-bit images divided by 255; 16-bit PNG by 65535).

    Raises
    ------
    ImageLoadError
        Missing file, too many bytes, not PNG/JPEG, more than *max_pixels* pixels, a decompression
        bomb, a truncated/corrupt file, or an unusable colour profile.
    """
    p = Path(path)
    if not p.is_file():
        raise ImageLoadError("image", "an existing PNG or JPEG file", str(p))
    size = p.stat().st_size
    if size > max_bytes:
        raise ImageLoadError("image", f"a file of at most {max_bytes} bytes", size)
    return _decode(p, p.suffix, max_pixels).to_float()


def save_png(path: str | Path, encoded: NDArray) -> Path:
    """Write sRGB-encoded values in [0, 1] (or uint8) to a PNG with an sRGB ICC profile."""
    arr = np.asarray(encoded)
    if arr.dtype != np.uint8:
        arr = np.floor(np.clip(arr.astype(float), 0, 1) * 255.0 + 0.5).astype(np.uint8)
    icc = ImageCms.ImageCmsProfile(ImageCms.createProfile("sRGB")).tobytes()
    p = Path(path)
    Image.fromarray(arr, "RGB").save(p, format="PNG", icc_profile=icc)
    return p
