"""Virtual mood board (thesis §3.5): boards of images, face/flop eyedroppers and the gloss eyedropper.

Images are sRGB-encoded float arrays ``(H, W, 3)`` in [0, 1] (:func:`station.design.images.load_image`
makes them from files); pixel positions are ``(x, y)`` = (column, row).
"""

from __future__ import annotations

import json
import math
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from station.design.errors import DesignInputError
from station.model import GLOSS_MAX_GU, GLOSS_MIN_GU, FaceFlopTravelGloss
from station.model.colorimetry import REC709_LUMINANCE
from station.model.design_io import design_to_dict
from station.model.display import display_to_lab

#: Accepted eyedropper radius (pixels).
RADIUS_MAX = 64
#: Gloss eyedropper: contrast of 0.5 maps to 100 GU (thesis §3.5.3, chosen there by trial and error).
CONTRAST_FULL_SCALE = 0.5
TAIL_FRACTION = 0.10


# ----------------------------------------------------------------------------------------- boards


@dataclass(frozen=True)
class BoardImage:
    """One image pinned on a board: file path, top-left position (board pixels) and zoom (> 0)."""

    path: str
    x: float = 0.0
    y: float = 0.0
    zoom: float = 1.0

    def __post_init__(self) -> None:
        for name in ("x", "y", "zoom"):
            v = getattr(self, name)
            if not isinstance(v, (int, float)) or not math.isfinite(v):
                raise DesignInputError(name, "a finite number", v)
        if not 0.01 <= self.zoom <= 100.0:
            raise DesignInputError("zoom", "0.01 <= zoom <= 100", self.zoom)


@dataclass(frozen=True)
class Board:
    """A named board (one tab of the mood board, thesis §3.5.1) holding images."""

    name: str
    images: tuple[BoardImage, ...] = ()

    def add(self, image: BoardImage) -> Board:
        """Return the board with *image* pinned on top."""
        return Board(self.name, (*self.images, image))

    def move(self, index: int, x: float, y: float) -> Board:
        """Return the board with image *index* dragged to (*x*, *y*)."""
        self._check_index(index)
        imgs = list(self.images)
        imgs[index] = BoardImage(imgs[index].path, x, y, imgs[index].zoom)
        return Board(self.name, tuple(imgs))

    def zoom(self, index: int, zoom: float) -> Board:
        """Return the board with image *index* zoomed to *zoom*."""
        self._check_index(index)
        imgs = list(self.images)
        imgs[index] = BoardImage(imgs[index].path, imgs[index].x, imgs[index].y, zoom)
        return Board(self.name, tuple(imgs))

    def _check_index(self, index: int) -> None:
        if not 0 <= index < len(self.images):
            raise DesignInputError("index", f"0 <= index < {len(self.images)}", index)


@dataclass(frozen=True)
class MoodBoard:
    """Several named boards; JSON round trip with :meth:`to_json` / :meth:`from_json`."""

    boards: tuple[Board, ...] = field(default_factory=tuple)

    def __post_init__(self) -> None:
        names = [b.name for b in self.boards]
        if len(set(names)) != len(names):
            raise DesignInputError("boards", "unique board names", names)

    def board(self, name: str) -> Board:
        """Return the board called *name*."""
        for b in self.boards:
            if b.name == name:
                return b
        raise DesignInputError("name", f"one of {[b.name for b in self.boards]}", name)

    def with_board(self, board: Board) -> MoodBoard:
        """Return the mood board with *board* added or replacing the one of the same name."""
        rest = tuple(b for b in self.boards if b.name != board.name)
        return MoodBoard((*rest, board))

    def to_dict(self) -> dict[str, Any]:
        """Plain JSON-able dict (schema ``cacad.moodboard/1``)."""
        return {"schema": "cacad.moodboard/1", "boards": [asdict(b) for b in self.boards]}

    def to_json(self) -> str:
        """Serialise to JSON text."""
        return json.dumps(self.to_dict(), indent=2)

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> MoodBoard:
        """Rebuild from :meth:`to_dict` output (validates every field)."""
        if not isinstance(data, dict) or data.get("schema") != "cacad.moodboard/1":
            raise DesignInputError(
                "schema", "cacad.moodboard/1", data.get("schema") if isinstance(data, dict) else data
            )
        try:
            boards = tuple(
                Board(
                    str(b["name"]),
                    tuple(BoardImage(str(i["path"]), i["x"], i["y"], i["zoom"]) for i in b["images"]),
                )
                for b in data["boards"]
            )
        except (KeyError, TypeError) as exc:
            raise DesignInputError(
                "boards", "a list of {name, images: [{path, x, y, zoom}]}", None, str(exc)
            ) from exc
        return cls(boards)

    @classmethod
    def from_json(cls, text: str) -> MoodBoard:
        """Parse JSON text written by :meth:`to_json`."""
        try:
            return cls.from_dict(json.loads(text))
        except json.JSONDecodeError as exc:
            raise DesignInputError("moodboard", "JSON text", None, str(exc)) from exc

    def save(self, path: str | Path) -> None:
        """Write the JSON to *path*."""
        Path(path).write_text(self.to_json())

    @classmethod
    def load(cls, path: str | Path) -> MoodBoard:
        """Read a mood board written by :meth:`save`."""
        return cls.from_json(Path(path).read_text())


# ------------------------------------------------------------------------------------- eyedroppers


def _check_image(image: ArrayLike) -> NDArray[np.float64]:
    """*image* as float64 sRGB in [0, 1]; an integer array (8- or 16-bit encoding) is divided by its
    dtype's full scale (255, 65535), so callers may hand over uint8 images and convert only windows."""
    raw = np.asarray(image)
    if raw.ndim != 3 or raw.shape[-1] != 3:
        raise DesignInputError("image", "an (H, W, 3) sRGB image", raw.shape)
    if raw.dtype.kind in "ui":
        return np.clip(raw.astype(np.float64) / float(np.iinfo(raw.dtype).max), 0.0, 1.0)
    img = np.asarray(raw, dtype=float)
    if not np.all(np.isfinite(img)) or img.min() < 0 or img.max() > 1:
        raise DesignInputError(
            "image", "sRGB-encoded values in [0, 1]", (float(np.nanmin(img)), float(np.nanmax(img)))
        )
    return img


def region(image: ArrayLike, xy: tuple[float, float], radius: int) -> NDArray[np.float64]:
    """Pixels of *image* within *radius* pixels of *xy* (a disc, clipped to the image), ``(n, 3)``,
    row-major. Only the disc's bounding window is read, converted and checked, so sampling a large
    image costs ``(2 radius + 1)²`` pixels of memory, not the image's size."""
    arr = np.asarray(image)
    if arr.ndim != 3 or arr.shape[-1] != 3:
        raise DesignInputError("image", "an (H, W, 3) sRGB image", arr.shape)
    if not isinstance(radius, (int, np.integer)) or not 0 <= radius <= RADIUS_MAX:
        raise DesignInputError("radius", f"integer 0..{RADIUS_MAX} pixels", radius)
    h, w = arr.shape[:2]
    try:
        x, y = float(xy[0]), float(xy[1])
    except (TypeError, ValueError, IndexError) as exc:
        raise DesignInputError("xy", "a pixel position (x, y)", xy) from exc
    if not (0 <= x < w and 0 <= y < h):
        raise DesignInputError("xy", f"0 <= x < {w}, 0 <= y < {h}", (x, y))
    cx, cy = int(x), int(y)
    x0, x1 = max(0, cx - radius), min(w, cx + radius + 1)
    y0, y1 = max(0, cy - radius), min(h, cy + radius + 1)
    window = _check_image(arr[y0:y1, x0:x1])
    yy, xx = np.mgrid[y0:y1, x0:x1]
    sel = (xx - cx) ** 2 + (yy - cy) ** 2 <= radius * radius
    return window[sel]


def robust_colour(pixels: ArrayLike) -> NDArray[np.float64]:
    """Per-channel median of sRGB-encoded pixels ``(n, 3)`` — a steady eyedropper reading (thesis §3.5.2)."""
    p = np.asarray(pixels, dtype=float).reshape(-1, 3)
    if p.shape[0] == 0:
        raise DesignInputError("pixels", "at least one pixel", 0)
    return np.median(p, axis=0)


def eyedrop_lab(image: ArrayLike, xy: tuple[float, float], radius: int = 3) -> NDArray[np.float64]:
    """Sample Lab (D65/10°) at *xy*: median sRGB over a disc of *radius* px → linear sRGB → Lab."""
    rgb = robust_colour(region(image, xy, radius))
    return np.asarray(display_to_lab(rgb), dtype=float)


def face_darker(face: ArrayLike, flop: ArrayLike) -> bool:
    """Whether the face (Lab at 15°) is darker (L*) than the flop — a retroreflective colour, rare enough
    that the eyedroppers swap the two unless told not to (thesis §3.5.2)."""
    return float(np.asarray(face, dtype=float)[0]) < float(np.asarray(flop, dtype=float)[0])


def auto_swap_design(design: FaceFlopTravelGloss) -> tuple[FaceFlopTravelGloss, bool]:
    """*design* with face and flop exchanged when the face is darker than the flop (thesis §3.5.2),
    and whether they were; travel and gloss are kept."""
    if not face_darker(design.face, design.flop):
        return design, False
    return design.replace(face=design.flop, flop=design.face), True


@dataclass(frozen=True)
class EyedropResult:
    """Design seeded by the eyedroppers, the sampled Labs and whether face and flop were swapped."""

    design: FaceFlopTravelGloss
    face_lab: tuple[float, float, float]
    flop_lab: tuple[float, float, float]
    swapped: bool
    gloss: ContrastGloss | None = None

    def to_dict(self, **extra: Any) -> dict[str, Any]:
        """JSON-ready form shared by every front: design (``cacad.design/1``), sampled Labs (D65/10°),
        *swapped*, then *extra* (e.g. the image's colour note), then the gloss reading when one was taken."""
        out: dict[str, Any] = {
            "design": design_to_dict(self.design),
            "face_lab": list(self.face_lab),
            "flop_lab": list(self.flop_lab),
            "swapped": self.swapped,
            **extra,
        }
        if self.gloss is not None:
            out["gloss"] = {
                "gloss_gu": self.gloss.gloss_gu,
                "contrast": self.gloss.contrast,
                "clipped": self.gloss.clipped,
            }
        return out


def eyedrop_design(
    image: ArrayLike,
    face_xy: tuple[float, float],
    flop_xy: tuple[float, float],
    travel_deg: float = 75.0,
    gloss_gu: float = 50.0,
    radius: int = 3,
    auto_swap: bool = True,
    gloss_xy: tuple[float, float] | None = None,
) -> EyedropResult:
    """Seed a face/flop/travel/gloss design from a mood-board image (thesis §3.5.2–§3.5.3).

    Face = Lab under *face_xy*, flop = Lab under *flop_xy*, travel from the slider (*travel_deg*,
    15 < travel <= 180), gloss from *gloss_gu* or, with *gloss_xy*, from :func:`contrast_gloss`.
    With *auto_swap* (the default) a face darker (L*) than the flop is swapped with it — retroreflective
    colours are rare; pass ``auto_swap=False`` to style one. Equal colours give a solid (no travel).
    """
    face_l, face_a, face_b = (float(v) for v in eyedrop_lab(image, face_xy, radius))
    flop_l, flop_a, flop_b = (float(v) for v in eyedrop_lab(image, flop_xy, radius))
    face, flop = (face_l, face_a, face_b), (flop_l, flop_a, flop_b)
    swapped = bool(auto_swap and face_darker(face, flop))
    if swapped:
        face, flop = flop, face
    gloss = None
    if gloss_xy is not None:
        gloss = contrast_gloss(region(image, gloss_xy, radius))
        gloss_gu = gloss.gloss_gu
    travel = None if face == flop else travel_deg
    try:
        design = FaceFlopTravelGloss(face, flop, travel, gloss_gu)
    except ValueError as exc:
        raise DesignInputError("eyedrop", "samples and travel the model accepts", None, str(exc)) from exc
    return EyedropResult(design, face, flop, swapped, gloss)


# ---------------------------------------------------------------------------------- gloss eyedropper


@dataclass(frozen=True)
class ContrastGloss:
    """Gloss eyedropper reading: gloss in GU, the raw contrast, and whether it was clipped at 100 GU."""

    gloss_gu: float
    contrast: float
    clipped: bool
    pixels: int


def brightness(encoded_rgb: ArrayLike) -> NDArray[np.float64]:
    """Brightness on 0–1 of sRGB-encoded pixels: Rec. 709 luma ``Y' = 0.2126 R' + 0.7152 G' + 0.0722 B'``."""
    p = np.asarray(encoded_rgb, dtype=float)
    return p @ REC709_LUMINANCE


def contrast_gloss(pixels: ArrayLike) -> ContrastGloss:
    """Contrast gloss of a small region (thesis §3.5.3).

    Mean brightness of the brightest 10 % of the pixels minus that of the darkest 10 % (each tail at
    least one pixel) is the contrast; 0–0.5 maps linearly to 0–100 GU, and a contrast above 0.5 reads
    100 GU with ``clipped=True`` (the thesis's rule; the clip is reported, not hidden).

    Limits (thesis §3.5.3, and shown by the tests): it is a rough guess for low-dynamic-range images of
    unknown lighting and geometry, valid only where the geometry is locally smooth. Surface texture
    (e.g. a black-and-white weave) and shadow boundaries produce high contrast and are read as high
    gloss, although neither is specular; a uniform region reads 0 GU whatever the true gloss (a matt
    colour and a mirror reflecting a uniform sky look the same). The user, not the code, must keep the
    eyedropper on highlights, their boundaries or dull areas.
    """
    p = np.asarray(pixels, dtype=float).reshape(-1, 3)
    if p.shape[0] < 2:
        raise DesignInputError("pixels", "at least 2 pixels", p.shape[0])
    y = np.sort(brightness(p))
    k = max(1, math.ceil(TAIL_FRACTION * y.size))
    contrast = float(y[-k:].mean() - y[:k].mean())
    raw = contrast / CONTRAST_FULL_SCALE * GLOSS_MAX_GU
    return ContrastGloss(min(raw, GLOSS_MAX_GU), contrast, raw > GLOSS_MAX_GU, int(y.size))


@dataclass(frozen=True)
class GlossBlend:
    """Gloss blended over consecutive eyedropper samples (exponential moving average, thesis §3.5.3)."""

    gloss_gu: float | None = None
    weight: float = 0.3
    samples: int = 0

    def __post_init__(self) -> None:
        if not 0.0 < self.weight <= 1.0:
            raise DesignInputError("weight", "0 < weight <= 1", self.weight)

    def update(self, sample: ContrastGloss | float) -> GlossBlend:
        """Return the blend after one more sample: ``g ← (1 − w) g + w·sample`` (first sample taken as is)."""
        g = sample.gloss_gu if isinstance(sample, ContrastGloss) else float(sample)
        if not math.isfinite(g) or not GLOSS_MIN_GU <= g <= GLOSS_MAX_GU:
            raise DesignInputError("sample", f"{GLOSS_MIN_GU:g} <= gloss_gu <= {GLOSS_MAX_GU:g}", g)
        new = g if self.gloss_gu is None else (1.0 - self.weight) * self.gloss_gu + self.weight * g
        return GlossBlend(new, self.weight, self.samples + 1)
