"""Reading and writing high-dynamic-range images: Radiance RGBE (.hdr) and OpenEXR (.exr).

Every reader returns scene-linear float32 RGB of shape (H, W, 3), row 0 at the top of the image,
and rejects anything that is not a usable HDR environment with
:class:`~station.render.errors.EnvironmentFileError`: LDR formats (PNG, JPEG, TIFF, BMP, GIF),
truncated or malformed files, absurd dimensions, and non-finite, negative, all-zero or huge values.

Radiance format (Greg Ward, *Real Pixels*, Graphics Gems II, 1991): a text header starting with
``#?RADIANCE`` or ``#?RGBE``, ``FORMAT=32-bit_rle_rgbe``, a blank line, a resolution line
``-Y H +X W``, then scanlines either flat (4 bytes per pixel) or "new" run-length encoded (marker
``2 2 hi lo``, then each of the four byte planes as runs: count > 128 repeats the next byte
count−128 times, otherwise count literal bytes follow). A pixel (r, g, b, e) decodes to
((r, g, b) + 0.5) · 2^(e − 136), e = 0 meaning black. ``EXPOSURE=`` values multiply into the
stored pixels, so they are divided out to recover the original radiance.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from station.render.errors import EnvironmentFileError

MAX_WIDTH = 32768
MAX_HEIGHT = 16384
MAX_PIXELS = 1 << 27
MAX_VALUE = 1.0e8  # larger radiance than this (relative units) is treated as corrupt
ACCEPTED = "a Radiance .hdr (32-bit_rle_rgbe) or OpenEXR .exr HDR image with finite non-negative RGB"

_LDR_MAGIC = {
    b"\x89PNG": "PNG",
    b"\xff\xd8\xff": "JPEG",
    b"II*\x00": "TIFF",
    b"MM\x00*": "TIFF",
    b"BM": "BMP",
    b"GIF8": "GIF",
}
_EXR_MAGIC = b"\x76\x2f\x31\x01"


def read_hdr_image(path: str | Path) -> np.ndarray:
    """Read a .hdr or .exr file (format sniffed from its first bytes) as float32 (H, W, 3)."""
    path = Path(path)
    try:
        with path.open("rb") as fh:
            head = fh.read(16)
    except OSError as exc:
        raise EnvironmentFileError(path, ACCEPTED, f"cannot read: {exc.strerror}") from exc
    for magic, name in _LDR_MAGIC.items():
        if head.startswith(magic):
            raise EnvironmentFileError(path, ACCEPTED, f"{name} is a low-dynamic-range format")
    if head.startswith(_EXR_MAGIC):
        image = _read_exr(path)
    elif head.startswith((b"#?RADIANCE", b"#?RGBE")):
        image = _read_radiance(path)
    else:
        raise EnvironmentFileError(path, ACCEPTED, "unrecognised file signature")
    validate_image(image, path)
    return image


def validate_image(image: np.ndarray, path: object = "<array>") -> None:
    """Raise EnvironmentFileError unless *image* is (H, W, 3), finite, ≥ 0, not all zero, not huge."""
    if image.ndim != 3 or image.shape[2] != 3:
        raise EnvironmentFileError(path, ACCEPTED, f"expected (H, W, 3) RGB, got shape {image.shape}")
    h, w = image.shape[:2]
    _check_dims(path, w, h)
    if not np.isfinite(image).all():
        raise EnvironmentFileError(path, ACCEPTED, "contains NaN or infinite values")
    lo, hi = float(image.min()), float(image.max())
    if lo < 0.0:
        raise EnvironmentFileError(path, ACCEPTED, f"contains negative radiance (min {lo:.4g})")
    if hi <= 0.0:
        raise EnvironmentFileError(path, ACCEPTED, "image is entirely black")
    if hi > MAX_VALUE:
        raise EnvironmentFileError(path, ACCEPTED, f"absurd radiance {hi:.4g} > {MAX_VALUE:.0e}")


def _check_dims(path: object, w: int, h: int) -> None:
    if not (1 <= w <= MAX_WIDTH and 1 <= h <= MAX_HEIGHT and w * h <= MAX_PIXELS):
        raise EnvironmentFileError(
            path, ACCEPTED, f"absurd dimensions {w}x{h} (max {MAX_WIDTH}x{MAX_HEIGHT}, {MAX_PIXELS} pixels)"
        )


def _read_exr(path: Path) -> np.ndarray:
    import OpenEXR

    try:
        with OpenEXR.File(str(path)) as exr:
            channels = exr.channels()
            if "RGB" in channels:
                rgb = np.asarray(channels["RGB"].pixels)
            elif {"R", "G", "B"} <= set(channels):
                rgb = np.stack([np.asarray(channels[c].pixels) for c in "RGB"], axis=-1)
            elif "RGBA" in channels:
                rgb = np.asarray(channels["RGBA"].pixels)[..., :3]
            else:
                raise EnvironmentFileError(path, ACCEPTED, f"no R, G, B channels (has {sorted(channels)})")
    except EnvironmentFileError:
        raise
    except Exception as exc:  # the OpenEXR binding raises ValueError/RuntimeError/OSError alike
        raise EnvironmentFileError(path, ACCEPTED, f"OpenEXR could not read it: {exc}") from exc
    if rgb.dtype.kind in "ui":
        raise EnvironmentFileError(path, ACCEPTED, f"integer channels ({rgb.dtype}) are not HDR")
    return np.ascontiguousarray(rgb, dtype=np.float32)


def _read_radiance(path: Path) -> np.ndarray:
    data = path.read_bytes()
    pos, exposure, fmt = 0, 1.0, None
    while True:
        end = data.find(b"\n", pos)
        if end < 0 or end - pos > 4096:
            raise EnvironmentFileError(path, ACCEPTED, "header not terminated")
        line = data[pos:end].strip()
        pos = end + 1
        if not line:
            break
        if line.startswith(b"FORMAT="):
            fmt = line[7:].decode("ascii", "replace")
        elif line.startswith(b"EXPOSURE="):
            try:
                exposure *= float(line[9:])
            except ValueError as exc:
                raise EnvironmentFileError(path, ACCEPTED, f"bad EXPOSURE line {line!r}") from exc
    if fmt not in (None, "32-bit_rle_rgbe"):
        raise EnvironmentFileError(path, ACCEPTED, f"unsupported FORMAT={fmt}")
    if not (exposure > 0.0 and np.isfinite(exposure)):
        raise EnvironmentFileError(path, ACCEPTED, f"absurd EXPOSURE {exposure}")
    end = data.find(b"\n", pos)
    parts = data[pos : end if end >= 0 else len(data)].split()
    if len(parts) != 4 or parts[0] not in (b"-Y", b"+Y") or parts[2] != b"+X":
        raise EnvironmentFileError(path, ACCEPTED, f"unsupported resolution line {data[pos:end][:60]!r}")
    try:
        h, w = int(parts[1]), int(parts[3])
    except ValueError as exc:
        raise EnvironmentFileError(path, ACCEPTED, "non-numeric resolution") from exc
    _check_dims(path, w, h)
    rgbe = _decode_scanlines(path, data, end + 1, w, h)
    if parts[0] == b"+Y":
        rgbe = rgbe[::-1]
    return (rgbe_to_float(rgbe) / np.float32(exposure)).astype(np.float32)


def _decode_scanlines(path: Path, data: bytes, pos: int, w: int, h: int) -> np.ndarray:
    out = np.empty((h, w, 4), dtype=np.uint8)
    n = len(data)
    for y in range(h):
        if pos + 4 > n:
            raise EnvironmentFileError(path, ACCEPTED, f"truncated at scanline {y} of {h}")
        if 8 <= w < 32768 and data[pos] == 2 and data[pos + 1] == 2 and data[pos + 2] < 128:
            if (data[pos + 2] << 8 | data[pos + 3]) != w:
                raise EnvironmentFileError(path, ACCEPTED, f"scanline {y} length mismatch")
            pos += 4
            for c in range(4):
                plane = bytearray()
                while len(plane) < w:
                    if pos >= n:
                        raise EnvironmentFileError(path, ACCEPTED, f"truncated at scanline {y} of {h}")
                    count = data[pos]
                    if count > 128:
                        if pos + 1 >= n:
                            raise EnvironmentFileError(path, ACCEPTED, f"truncated at scanline {y} of {h}")
                        plane += bytes((data[pos + 1],)) * (count - 128)
                        pos += 2
                    else:
                        if count == 0 or pos + 1 + count > n:
                            raise EnvironmentFileError(path, ACCEPTED, f"bad run-length data at scanline {y}")
                        plane += data[pos + 1 : pos + 1 + count]
                        pos += 1 + count
                if len(plane) != w:
                    raise EnvironmentFileError(path, ACCEPTED, f"run overflows scanline {y}")
                out[y, :, c] = np.frombuffer(bytes(plane), dtype=np.uint8)
        else:
            if data[pos] == 1 and data[pos + 1] == 1 and data[pos + 2] == 1:
                raise EnvironmentFileError(path, ACCEPTED, "old-style Radiance run-length encoding")
            if pos + 4 * w > n:
                raise EnvironmentFileError(path, ACCEPTED, f"truncated at scanline {y} of {h}")
            out[y] = np.frombuffer(data, dtype=np.uint8, count=4 * w, offset=pos).reshape(w, 4)
            pos += 4 * w
    return out


def rgbe_to_float(rgbe: np.ndarray) -> np.ndarray:
    """Decode (..., 4) uint8 RGBE to float32 RGB: ((r, g, b) + 0.5) · 2^(e − 136), black when e = 0."""
    e = rgbe[..., 3].astype(np.int32)
    scale = np.where(e > 0, np.ldexp(np.float32(1.0), e - 136), 0.0).astype(np.float32)
    return (rgbe[..., :3].astype(np.float32) + 0.5) * scale[..., None]


def float_to_rgbe(rgb: np.ndarray) -> np.ndarray:
    """Encode float RGB (..., 3) ≥ 0 to (..., 4) uint8 RGBE (Ward's frexp scheme)."""
    rgb = np.asarray(rgb, dtype=np.float64)
    peak = rgb.max(axis=-1)
    mant, expo = np.frexp(peak)
    out = np.zeros(rgb.shape[:-1] + (4,), dtype=np.uint8)
    ok = peak > 1e-32
    scale = np.where(ok, mant * 256.0 / np.where(ok, peak, 1.0), 0.0)
    out[..., :3] = np.clip(np.floor(rgb * scale[..., None]), 0, 255).astype(np.uint8)
    out[..., 3] = np.where(ok, expo + 128, 0).astype(np.uint8)
    return out


def write_hdr(path: str | Path, rgb: np.ndarray, rle: bool = True) -> None:
    """Write float RGB (H, W, 3) as a Radiance .hdr, run-length encoded (new RLE) or flat."""
    rgbe = float_to_rgbe(rgb)
    h, w = rgbe.shape[:2]
    chunks = [b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n", f"-Y {h} +X {w}\n".encode()]
    for y in range(h):
        if rle and 8 <= w < 32768:
            chunks.append(bytes((2, 2, w >> 8, w & 255)))
            for c in range(4):
                chunks.append(_rle_plane(rgbe[y, :, c].tobytes()))
        else:
            chunks.append(rgbe[y].tobytes())
    Path(path).write_bytes(b"".join(chunks))


def _rle_plane(plane: bytes) -> bytes:
    out, i, n = bytearray(), 0, len(plane)
    while i < n:
        j = i
        while j < n and j - i < 127 and plane[j] == plane[i]:
            j += 1
        if j - i >= 4:
            out += bytes((128 + j - i, plane[i]))
            i = j
            continue
        j = i
        while (
            j < n
            and j - i < 128
            and not (j + 3 < n and plane[j] == plane[j + 1] == plane[j + 2] == plane[j + 3])
        ):
            j += 1
        j = max(j, i + 1)
        out += bytes((j - i,)) + plane[i:j]
        i = j
    return bytes(out)


def write_exr(path: str | Path, rgb: np.ndarray, half: bool = False) -> None:
    """Write float RGB (H, W, 3) as a ZIP-compressed OpenEXR scanline file (float32 or half)."""
    import OpenEXR

    pixels = np.ascontiguousarray(rgb, dtype=np.float16 if half else np.float32)
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    with OpenEXR.File(header, {"RGB": pixels}) as exr:
        exr.write(str(path))
