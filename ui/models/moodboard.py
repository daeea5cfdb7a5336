"""Mood board state (Qt-free): boards of pinned images, and the face/flop/gloss eyedroppers.

Boards are :class:`station.design.moodboard.MoodBoard` values (immutable); pixels come from
:func:`station.design.images.load_image`. An eyedropper at board position (x, y) samples the image
under it (:func:`~station.design.moodboard.eyedrop_lab` / :func:`~station.design.moodboard.contrast_gloss`)
and edits the document with the designer operations (``move_face``, ``move_flop``, ``set_gloss``), one
undo step per drag.

Options (thesis §3.5.2–§3.5.3): ``auto_swap`` (default on) swaps face and flop when the sampled face is
darker than the flop; ``radius`` is the eyedropper disc (0–``RADIUS_MAX`` px); ``gloss_weight`` blends
the gloss eyedropper's samples over the frames of one drag (:class:`~station.design.moodboard.GlossBlend`,
1 = no blending). :meth:`MoodBoardModel.drop_pixels` samples pixels from elsewhere (the screen outside
the board).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from station.design.designer import move_face, move_flop, set_gloss
from station.design.images import load_image
from station.design.moodboard import (
    RADIUS_MAX,
    Board,
    BoardImage,
    GlossBlend,
    MoodBoard,
    auto_swap_design,
    contrast_gloss,
    eyedrop_lab,
    region,
)
from station.errors import InputError
from station.model import FaceFlopTravelGloss
from ui.models.document import DesignDocument
from ui.models.events import EventGroup

EYEDROPPERS = ("face", "flop", "gloss")
#: Default eyedropper radius (pixels).
RADIUS_PX = 3
#: Default weight of a new gloss sample in the blend over frames (GlossBlend's default).
GLOSS_WEIGHT = GlossBlend().weight


@dataclass(frozen=True)
class Hit:
    """An image under a board position: its index and the pixel (x, y) in image coordinates."""

    index: int
    x: float
    y: float


class MoodBoardModel:
    """Boards, the current board, loaded pixels and eyedropper positions.

    Events: ``board()`` when images are added, moved or zoomed, or the board changes;
    ``eyedropper(name, board_xy)`` when an eyedropper moves.
    """

    def __init__(self, document: DesignDocument, moodboard: MoodBoard | None = None) -> None:
        self.document = document
        self.moodboard = moodboard or MoodBoard((Board("board 1"),))
        self.current = self.moodboard.boards[0].name
        self.pixels: dict[str, np.ndarray] = {}
        self.eyedroppers: dict[str, tuple[float, float]] = {}
        self.events = EventGroup("board", "eyedropper")
        self.auto_swap = True
        self._radius = RADIUS_PX
        self._gloss_weight = GLOSS_WEIGHT
        #: Lab last read by the face and flop eyedroppers (before any swap).
        self.samples: dict[str, tuple[float, float, float]] = {}
        #: Whether the last face/flop drop swapped face and flop.
        self.swapped = False
        self._base: FaceFlopTravelGloss | None = None
        self._blend: GlossBlend | None = None

    @property
    def radius(self) -> int:
        """Eyedropper disc radius in pixels (0 = one pixel)."""
        return self._radius

    @radius.setter
    def radius(self, value: int) -> None:
        if not isinstance(value, int) or isinstance(value, bool) or not 0 <= value <= RADIUS_MAX:
            raise InputError("radius", f"integer 0..{RADIUS_MAX} pixels", value)
        self._radius = value

    @property
    def gloss_weight(self) -> float:
        """Weight of each new gloss sample in the blend over a drag's frames (0 < w <= 1; 1 = none)."""
        return self._gloss_weight

    @gloss_weight.setter
    def gloss_weight(self, value: float) -> None:
        GlossBlend(weight=value)  # validates 0 < weight <= 1
        self._gloss_weight = float(value)

    def load(self, moodboard: MoodBoard, base_dir: str | Path | None = None) -> None:
        """Replace every board with *moodboard*, loading its images (relative paths against *base_dir*).

        All images are loaded first: when one cannot be, the error propagates and nothing is changed.
        """
        if not moodboard.boards:
            moodboard = MoodBoard((Board("board 1"),))
        base = Path(base_dir) if base_dir is not None else None
        boards, pixels = [], {}
        for b in moodboard.boards:
            images = []
            for im in b.images:
                p = Path(im.path)
                if base is not None and not p.is_absolute():
                    p = base / p
                key = str(p)
                if key not in pixels:
                    pixels[key] = self.pixels[key] if key in self.pixels else load_image(key).pixels
                images.append(BoardImage(key, im.x, im.y, im.zoom))
            boards.append(Board(b.name, tuple(images)))
        self.moodboard = MoodBoard(tuple(boards))
        self.pixels = pixels
        self.current = self.moodboard.boards[0].name
        self.eyedroppers.clear()
        self.samples.clear()
        self.events.board.emit()

    @property
    def board(self) -> Board:
        """The board shown."""
        return self.moodboard.board(self.current)

    def _set_board(self, board: Board) -> None:
        self.moodboard = self.moodboard.with_board(board)
        self.events.board.emit()

    def add_board(self, name: str) -> None:
        """Add an empty board and show it."""
        if name in [b.name for b in self.moodboard.boards]:
            raise InputError("name", "a board name not used yet", name)
        self.moodboard = self.moodboard.with_board(Board(name))
        self.current = name
        self.events.board.emit()

    def select(self, name: str) -> None:
        """Show board *name*."""
        self.moodboard.board(name)
        self.current = name
        self.eyedroppers.clear()
        self.samples.clear()
        self.events.board.emit()

    def add_image(self, path: str, x: float = 0.0, y: float = 0.0, zoom: float = 1.0) -> None:
        """Load and pin an image (errors from the loader propagate: unreadable, too large…)."""
        if path not in self.pixels:
            self.pixels[path] = load_image(path).pixels
        self._set_board(self.board.add(BoardImage(path, x, y, zoom)))

    def move_image(self, index: int, x: float, y: float) -> None:
        """Drag image *index* to board position (x, y)."""
        self._set_board(self.board.move(index, x, y))

    def zoom_image(self, index: int, zoom: float) -> None:
        """Zoom image *index* (0.01–100)."""
        self._set_board(self.board.zoom(index, zoom))

    def image_rect(self, index: int) -> tuple[float, float, float, float]:
        """Board rectangle (x, y, w, h) of image *index*."""
        im = self.board.images[index]
        h, w = self.pixels[im.path].shape[:2]
        return im.x, im.y, w * im.zoom, h * im.zoom

    def hit(self, x: float, y: float) -> Hit | None:
        """The topmost image under board position (x, y), or None."""
        for i in range(len(self.board.images) - 1, -1, -1):
            im = self.board.images[i]
            if im.path not in self.pixels:
                continue
            rx, ry, rw, rh = self.image_rect(i)
            if rx <= x < rx + rw and ry <= y < ry + rh:
                return Hit(i, (x - rx) / im.zoom, (y - ry) / im.zoom)
        return None

    def sample_lab(self, x: float, y: float) -> np.ndarray | None:
        """Lab under board position (x, y) (median over the eyedropper disc), or None off the images."""
        h = self.hit(x, y)
        if h is None:
            return None
        return eyedrop_lab(self.pixels[self.board.images[h.index].path], (h.x, h.y), self.radius)

    def drop(self, name: str, x: float, y: float) -> bool:
        """Move eyedropper *name* to board position (x, y) and edit the design from what it samples.

        ``face``/``flop`` set that colour (L*, a*, b*; with ``auto_swap`` a face darker than the flop is
        swapped with it, thesis §3.5.2); ``gloss`` sets the contrast gloss of the region blended over the
        drag (thesis §3.5.3). False when off the images or refused by the core.
        """
        self._check_name(name)
        self.eyedroppers[name] = (x, y)
        self.events.eyedropper.emit(name, (x, y))
        h = self.hit(x, y)
        if h is None:
            return False
        return self._sample(name, self.pixels[self.board.images[h.index].path], (h.x, h.y))

    def drop_pixels(self, name: str, pixels: np.ndarray, xy: tuple[float, float]) -> bool:
        """Eyedropper *name* reading *pixels* (an sRGB image, e.g. the screen around the cursor outside
        the board) at *xy* (column, row) of that image; the same edit as :meth:`drop`."""
        self._check_name(name)
        return self._sample(name, pixels, xy)

    def _check_name(self, name: str) -> None:
        if name not in EYEDROPPERS:
            raise InputError("eyedropper", " | ".join(EYEDROPPERS), name)
        if self._base is None:  # first sample of a drag: edits are relative to the design now
            self._base = self.document.design
            self._blend = GlossBlend(weight=self.gloss_weight)

    def _sample(self, name: str, img: np.ndarray, xy: tuple[float, float]) -> bool:
        try:
            if name == "gloss":
                blend = (self._blend or GlossBlend(weight=self.gloss_weight)).update(
                    contrast_gloss(region(img, xy, self.radius))
                )
                self._blend = blend
                g = float(blend.gloss_gu or 0.0)
                return self.document.apply(
                    lambda d: set_gloss(d, g), "gloss eyedropper", merge_key="eye:gloss"
                )
            L, a, b = (float(v) for v in eyedrop_lab(img, xy, self.radius))
        except InputError as exc:
            self.document.events.error.emit(str(exc))
            return False
        self.samples[name] = (L, a, b)
        base = self._base if self._base is not None else self.document.design
        face = self.samples.get("face", base.face)
        flop = self.samples.get("flop", base.flop)

        def op(_d: FaceFlopTravelGloss) -> FaceFlopTravelGloss:
            d = move_face(move_flop(base, flop[1], flop[2], flop[0]), face[1], face[2], face[0])
            if self.auto_swap:
                d, self.swapped = auto_swap_design(d)
            else:
                self.swapped = False
            return d

        return self.document.apply(op, f"{name} eyedropper", merge_key=f"eye:{name}")

    def end_drop(self) -> None:
        """Eyedropper released: the drag is one undo step."""
        self._base = None
        self._blend = None
        self.document.end_merge()
