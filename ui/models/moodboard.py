"""Mood board state (Qt-free): boards of pinned images, and the face/flop/gloss eyedroppers.

Boards are :class:`station.design.moodboard.MoodBoard` values (immutable); pixels come from
:func:`station.design.images.load_image`. An eyedropper at board position (x, y) samples the image
under it (:func:`~station.design.moodboard.eyedrop_lab` / :func:`~station.design.moodboard.contrast_gloss`)
and edits the document with the designer operations (``move_face``, ``move_flop``, ``set_gloss``), one
undo step per drag.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from station.design.designer import move_face, move_flop, set_gloss
from station.design.images import load_image
from station.design.moodboard import Board, BoardImage, MoodBoard, contrast_gloss, eyedrop_lab, region
from station.errors import InputError
from ui.models.document import DesignDocument
from ui.models.events import EventGroup

EYEDROPPERS = ("face", "flop", "gloss")
RADIUS_PX = 3


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
        """Lab under board position (x, y) (median over a 3-pixel disc), or None off the images."""
        h = self.hit(x, y)
        if h is None:
            return None
        return eyedrop_lab(self.pixels[self.board.images[h.index].path], (h.x, h.y), RADIUS_PX)

    def drop(self, name: str, x: float, y: float) -> bool:
        """Move eyedropper *name* to board position (x, y) and edit the design from what it samples.

        ``face``/``flop`` set that colour (``move_face``/``move_flop``, L*, a*, b*); ``gloss`` sets the
        contrast gloss of the region (thesis §3.5.3). False when off the images or refused by the core.
        """
        if name not in EYEDROPPERS:
            raise InputError("eyedropper", " | ".join(EYEDROPPERS), name)
        self.eyedroppers[name] = (x, y)
        self.events.eyedropper.emit(name, (x, y))
        h = self.hit(x, y)
        if h is None:
            return False
        img = self.pixels[self.board.images[h.index].path]
        if name == "gloss":
            g = contrast_gloss(region(img, (h.x, h.y), RADIUS_PX)).gloss_gu
            return self.document.apply(lambda d: set_gloss(d, g), "gloss eyedropper", merge_key="eye:gloss")
        L, a, b = (float(v) for v in eyedrop_lab(img, (h.x, h.y), RADIUS_PX))
        op = move_face if name == "face" else move_flop
        return self.document.apply(lambda d: op(d, a, b, L), f"{name} eyedropper", merge_key=f"eye:{name}")

    def end_drop(self) -> None:
        """Eyedropper released: the drag is one undo step."""
        self.document.end_merge()
