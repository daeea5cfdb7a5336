"""Designer state on top of a :class:`~ui.models.document.DesignDocument` (Qt-free).

Each method wraps one pure operation of :mod:`station.design` and records it as an undoable edit.
Drags (a plot point, the HSB sliders) merge into one undo step until :meth:`end_drag`.

:class:`VariationSwatches` renders the variations (thesis §3.4.4) on the object of the main view: the
picture is linear in the paint's lobe weights, so the main view's cached basis images
(:mod:`station.render.basis_images`), sampled once on a square grid around the object, give each
variation's swatch as one small re-weighting (``BasisImages.linear_image``) and a box filter.
"""

from __future__ import annotations

import numpy as np

# the methods below bear the names of the operations they wrap: called through the module, never confused
from station.design import designer as ops
from station.design.designer import Channel
from station.design.variations import Category, VariationRing, variations
from station.errors import InputError
from station.model import ANGLES_5, FaceFlopTravelGloss
from station.render.basis_images import BasisImages, build_basis_images
from station.render.tonemap import to_display
from ui.models.document import DesignDocument
from ui.models.events import EventGroup
from ui.models.view import (
    PREFILTER_MAX_SIZE,
    PREVIEW_PREFILTER_SIZE,
    ViewSettings,
    environment_basis,
    environment_ready,
    paint_weights,
)

#: Margin around the object's bounding box in a swatch (fraction of the box's longer side, each side).
SWATCH_MARGIN = 0.06
#: Most samples per swatch pixel along x and y (box filter in linear radiance).
SWATCH_SUPERSAMPLE = 4
#: Pixels (square) of the view rendered for the swatches when the main view has no current basis.
OWN_BASIS_PX = 160


class SwatchInputError(InputError):
    """A swatch size or supersampling factor out of range (field name and accepted range)."""


def swatch_basis(source: BasisImages, size: int, supersample: int = SWATCH_SUPERSAMPLE) -> BasisImages:
    """The basis images of *source* sampled on a square grid of (size·s)² points around the object.

    The square is centred on the object's bounding box (its pixels in ``source.pixels``), with side
    ``max(box width, box height)·(1 + 2·SWATCH_MARGIN)`` pixels; each grid point takes the nearest view
    pixel (clamped into the frame). s = min(*supersample*, ⌊side / size⌋) ≥ 1 samples per swatch pixel
    along each axis. The result is a :class:`BasisImages` of (size·s)² pixels (``width == height ==
    size·s``) whose paint halves, N·V and background are those of the sampled pixels, so
    ``linear_image`` of it is the view's radiance at the grid points (exactly: the core's sum).
    """
    if not 4 <= int(size) <= 1024:
        raise SwatchInputError("size", "4 <= size <= 1024 pixels", size)
    if not 1 <= int(supersample) <= 16:
        raise SwatchInputError("supersample", "1 <= supersample <= 16", supersample)
    w, h = source.width, source.height
    if source.pixels.size == 0:  # nothing of the object in view: the background alone
        ys, xs = np.array([0, h - 1]), np.array([0, w - 1])
    else:
        ys, xs = np.divmod(source.pixels, w)
    x0, x1, y0, y1 = xs.min(), xs.max() + 1, ys.min(), ys.max() + 1
    side = max(x1 - x0, y1 - y0) * (1.0 + 2.0 * SWATCH_MARGIN)
    s = max(1, min(int(supersample), int(side // size)))
    n = int(size) * s
    t = (np.arange(n) + 0.5) / n - 0.5
    gx = np.clip(np.floor((x0 + x1) / 2.0 + t * side), 0, w - 1).astype(np.int64)
    gy = np.clip(np.floor((y0 + y1) / 2.0 + t * side), 0, h - 1).astype(np.int64)
    flat = (gy[:, None] * w + gx[None, :]).reshape(-1)  # view pixel of each grid point, row-major
    where = np.full(w * h, -1, np.int64)
    where[source.pixels] = np.arange(source.pixels.size)
    j = where[flat]
    grid = np.arange(n * n)
    first = (j >= 0) & (j < source.split)
    second = j >= source.split
    take = np.concatenate([j[first], j[second]])
    background = None if source.background is None else source.background[flat]
    return BasisImages(
        source.basis,
        n,
        n,
        np.concatenate([grid[first], grid[second]]),
        int(np.count_nonzero(first)),
        np.ascontiguousarray(source.images[:, :, take]),
        source.n_dot_v[take],
        source.layout,
        background=background,
    )


class VariationSwatches:
    """Swatches of designs rendered on the object of the main view, *size* × *size* pixels.

    :meth:`use` takes the view's cached basis images (the core's :class:`BasisImages`, any size) and
    samples them once (:func:`swatch_basis`); :meth:`render` then costs one small re-weighting per
    design. Without a view basis, :meth:`use_settings` ray-casts the view itself at OWN_BASIS_PX² (same
    shape, camera, environment, stage and coat; the coarse prefilter while the full one is not in memory).
    """

    def __init__(self, size: int, supersample: int = SWATCH_SUPERSAMPLE) -> None:
        self.size = int(size)
        self.supersample = int(supersample)
        self.source: BasisImages | None = None
        self.sampled: BasisImages | None = None
        self.own_settings: ViewSettings | None = None
        self._own: dict[tuple[ViewSettings, int], BasisImages] = {}

    def use(self, source: BasisImages) -> bool:
        """Sample *source* (the main view's basis images) unless it is the one in use; True if new."""
        if source is self.source:
            return False
        self.source = source
        self.own_settings = None
        self.sampled = swatch_basis(source, self.size, self.supersample)
        return True

    def use_settings(self, settings: ViewSettings) -> bool:
        """Render the basis of *settings* at OWN_BASIS_PX² (kept per settings); True if new."""
        prefilter = PREFILTER_MAX_SIZE if environment_ready(settings.environment) else PREVIEW_PREFILTER_SIZE
        key = (settings, prefilter)
        own = self._own.get(key)
        if own is None:
            env = environment_basis(settings.environment, prefilter)
            own = build_basis_images(
                settings.scene(), env, OWN_BASIS_PX, OWN_BASIS_PX, coat=settings.clear_coat()
            )
            self._own = {key: own}  # only the latest view is worth keeping
        changed = self.use(own)
        self.own_settings = settings
        return changed

    def render(self, design: FaceFlopTravelGloss, exposure_ev: float = 0.0) -> np.ndarray:
        """8-bit sRGB swatch (size, size, 3) of *design* on both paint halves: the sampled radiance
        box-filtered in linear sRGB (mean of s × s samples), then ``tonemap.to_display`` at
        *exposure_ev* (EV), as the main view encodes its frame."""
        if self.sampled is None:
            raise SwatchInputError("source", "a view basis (use or use_settings first)", None)
        w = paint_weights(design)
        lin = self.sampled.linear_image([w, w])
        s = self.sampled.width // self.size
        lin = lin.reshape(self.size, s, self.size, s, 3).mean(axis=(1, 3))
        return to_display(lin, exposure_ev)


class DesignerModel:
    """Designer operations and the palette of kept designs. Events: ``palette()`` when it changes."""

    def __init__(self, document: DesignDocument) -> None:
        self.document = document
        self.palette: list[tuple[str, FaceFlopTravelGloss]] = []
        self._hsb_base: FaceFlopTravelGloss | None = None
        self._arrow_base: FaceFlopTravelGloss | None = None
        self.events = EventGroup("palette")

    @property
    def design(self) -> FaceFlopTravelGloss:
        """The current design."""
        return self.document.design

    def points(self) -> tuple[tuple[float, ...], tuple[tuple[float, float, float], ...]]:
        """Editable data points: (angles, Lab per angle) at the 5-angle set."""
        p = ops.data_points(self.design, ANGLES_5)
        return p.angles_deg, p.lab

    def move_point(self, channel: Channel, angle_deg: float, value: float) -> bool:
        """Drag the *channel* point at *angle_deg* to *value* and refit (thesis §3.4.1)."""
        return self.document.apply(
            lambda d: ops.move_point(ops.data_points(d, ANGLES_5), channel, angle_deg, value).design,
            f"move {channel} at {angle_deg:g}°",
            merge_key=f"point:{channel}:{angle_deg:g}",
        )

    def move_face(self, a: float, b: float) -> bool:
        """Drag the arrowhead (face) in the a–b plane (thesis §3.4.3)."""
        return self.document.apply(lambda d: ops.move_face(d, a, b), "move face", merge_key="face")

    def move_flop(self, a: float, b: float) -> bool:
        """Drag the arrow base (flop) in the a–b plane."""
        return self.document.apply(lambda d: ops.move_flop(d, a, b), "move flop", merge_key="flop")

    def move_arrow(self, da: float, db: float) -> bool:
        """Drag the whole face→flop arrow by (*da*, *db*) from where the drag started (thesis §3.4.3)."""
        if self._arrow_base is None:
            self._arrow_base = self.design
        base = self._arrow_base
        return self.document.apply(lambda _d: ops.move_arrow(base, da, db), "move arrow", merge_key="arrow")

    def set_lab(self, which: str, lab: tuple[float, float, float]) -> bool:
        """Type the face or flop Lab (L*, a*, b*, D65/10°); the core checks the domain."""
        op = ops.move_face if which == "face" else ops.move_flop
        L, a, b = lab
        return self.document.apply(lambda d: op(d, a, b, L), f"type {which} Lab")

    def set_travel(self, travel_deg: float) -> bool:
        """Set θ_clamp."""
        return self.document.apply(lambda d: ops.set_travel(d, travel_deg), "travel", merge_key="travel")

    def set_gloss(self, gloss_gu: float) -> bool:
        """Gloss slider (GU, 60°)."""
        return self.document.apply(lambda d: ops.set_gloss(d, gloss_gu), "gloss", merge_key="gloss")

    def set_hsb(self, hue_deg: float, saturation: float, brightness: float) -> bool:
        """HSB group edit relative to the design when the drag started (thesis §3.4.2)."""
        if self._hsb_base is None:
            self._hsb_base = self.design
        base = self._hsb_base
        return self.document.apply(
            lambda _d: ops.hsb_edit(base, hue_deg, saturation, brightness), "hue/sat/bright", merge_key="hsb"
        )

    def end_drag(self) -> None:
        """Mouse released: close the merged undo step and forget the HSB base."""
        self._hsb_base = None
        self._arrow_base = None
        self.document.end_merge()

    def variations(self, category: Category, degree: float) -> VariationRing:
        """Ring of variations around the current design (thesis §3.4.4)."""
        return variations(self.design, degree, category)

    def accept(self, design: FaceFlopTravelGloss, label: str = "accept variation") -> None:
        """Make *design* current (variation click, palette click)."""
        self.document.set_design(design, label)

    def keep(self, name: str | None = None) -> None:
        """Add the current design to the palette."""
        self.palette.append((name or f"swatch {len(self.palette) + 1}", self.design))
        self.events.palette.emit()
