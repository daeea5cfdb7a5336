"""Designer state on top of a :class:`~ui.models.document.DesignDocument` (Qt-free).

Each method wraps one pure operation of :mod:`station.design` and records it as an undoable edit.
Drags (a plot point, the HSB sliders) merge into one undo step until :meth:`end_drag`.
"""

from __future__ import annotations

from station.design.designer import (
    Channel,
    data_points,
    hsb_edit,
    move_arrow,
    move_face,
    move_flop,
    move_point,
    set_gloss,
    set_travel,
)
from station.design.variations import Category, VariationRing, variations
from station.model import ANGLES_5, FaceFlopTravelGloss
from ui.models.document import DesignDocument
from ui.models.events import EventGroup


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
        p = data_points(self.design, ANGLES_5)
        return p.angles_deg, p.lab

    def move_point(self, channel: Channel, angle_deg: float, value: float) -> bool:
        """Drag the *channel* point at *angle_deg* to *value* and refit (thesis §3.4.1)."""
        return self.document.apply(
            lambda d: move_point(data_points(d, ANGLES_5), channel, angle_deg, value).design,
            f"move {channel} at {angle_deg:g}°",
            merge_key=f"point:{channel}:{angle_deg:g}",
        )

    def move_face(self, a: float, b: float) -> bool:
        """Drag the arrowhead (face) in the a–b plane (thesis §3.4.3)."""
        return self.document.apply(lambda d: move_face(d, a, b), "move face", merge_key="face")

    def move_flop(self, a: float, b: float) -> bool:
        """Drag the arrow base (flop) in the a–b plane."""
        return self.document.apply(lambda d: move_flop(d, a, b), "move flop", merge_key="flop")

    def move_arrow(self, da: float, db: float) -> bool:
        """Drag the whole face→flop arrow by (*da*, *db*) from where the drag started (thesis §3.4.3)."""
        if self._arrow_base is None:
            self._arrow_base = self.design
        base = self._arrow_base
        return self.document.apply(lambda _d: move_arrow(base, da, db), "move arrow", merge_key="arrow")

    def set_lab(self, which: str, lab: tuple[float, float, float]) -> bool:
        """Type the face or flop Lab (L*, a*, b*, D65/10°); the core checks the domain."""
        op = move_face if which == "face" else move_flop
        L, a, b = lab
        return self.document.apply(lambda d: op(d, a, b, L), f"type {which} Lab")

    def set_travel(self, travel_deg: float) -> bool:
        """Set θ_clamp."""
        return self.document.apply(lambda d: set_travel(d, travel_deg), "travel", merge_key="travel")

    def set_gloss(self, gloss_gu: float) -> bool:
        """Gloss slider (GU, 60°)."""
        return self.document.apply(lambda d: set_gloss(d, gloss_gu), "gloss", merge_key="gloss")

    def set_hsb(self, hue_deg: float, saturation: float, brightness: float) -> bool:
        """HSB group edit relative to the design when the drag started (thesis §3.4.2)."""
        if self._hsb_base is None:
            self._hsb_base = self.design
        base = self._hsb_base
        return self.document.apply(
            lambda _d: hsb_edit(base, hue_deg, saturation, brightness), "hue/sat/bright", merge_key="hsb"
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
