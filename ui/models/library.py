"""Library browser state (Qt-free): filter, hierarchy, ColorSnap of the current design, match designs.

Everything numeric is the formulation core's: :class:`station.formulate.library.LibraryFilter`,
:func:`~station.formulate.library.hierarchy_counts`, :func:`station.formulate.snap.color_snap`; a library
paint becomes a design with ``station.model.fit_fftg`` on its measured angles.
"""

from __future__ import annotations

from dataclasses import replace
from functools import lru_cache
from typing import Any

import numpy as np

from station.design.palette import booklet
from station.formulate.library import Library, LibraryFilter, hierarchy_counts
from station.formulate.snap import SnapIndex, SnapResult, color_snap
from station.model import AspecularMeasurements, FaceFlopTravelGloss, fit_fftg
from station.model.display import lab_to_display
from station.model.domain import ANGLES_3
from ui.models.events import EventGroup

SNAP_ANGLES = ANGLES_3


def paint_design(library: Library, i: int) -> FaceFlopTravelGloss:
    """FFTG fit of library paint *i* through its measured angles (eqs 3.3.1–3.3.10)."""
    order = np.argsort(library.angles_deg)
    angles = tuple(float(library.angles_deg[j]) for j in order)
    return fit_fftg(AspecularMeasurements(angles, library.lab[i][order], float(library.gloss_gu[i]))).design


def bar_images(library: Library, rows: np.ndarray, width: int = 64, height: int = 14) -> np.ndarray:
    """Gradient thumbnails (len(rows), height, width, 3) uint8: Lab interpolated 15° → 110° (display only)."""
    order = np.argsort(library.angles_deg)
    angles = np.asarray(library.angles_deg)[order]
    lab = library.lab[rows][:, order]  # (n, k, 3)
    t = np.linspace(15.0, 110.0, width)
    cols = np.stack(
        [np.stack([np.interp(t, angles, lab[n, :, c]) for c in range(3)], -1) for n in range(len(rows))]
    )
    rgb = np.round(lab_to_display(cols) * 255).astype(np.uint8)
    return np.repeat(rgb[:, None], height, axis=1)


class LibraryModel:
    """A library, the browser filter and the last ColorSnap result. Events: ``filtered()``, ``snapped(result)``."""

    def __init__(self, library: Library) -> None:
        self.library = library
        self.filter = LibraryFilter()
        self.mask = np.ones(len(library), bool)
        self.snap_result: SnapResult | None = None
        self._index = SnapIndex(library)
        self.events = EventGroup("filtered", "snapped")

    def counts(self) -> dict[str, dict[str, dict[str, int]]]:
        """Hierarchy counts of the whole library (thesis Fig. 5.3)."""
        return hierarchy_counts(self.library)

    def index_range(self, name: str) -> tuple[float, float]:
        """Min and max of a defined index over the library (for slider ranges)."""
        v = self.library.indices()[name]
        v = v[np.isfinite(v)]
        return (float(v.min()), float(v.max())) if v.size else (0.0, 1.0)

    def set_filter(self, **kw: Any) -> None:
        """Replace filter fields (validated by LibraryFilter) and recompute the mask."""
        self.filter = replace(self.filter, **kw)
        self.mask = self.filter.mask(self.library)
        self.events.filtered.emit()

    @property
    def rows(self) -> np.ndarray:
        """Library rows passing the filter."""
        return np.flatnonzero(self.mask)

    def snap(self, design: FaceFlopTravelGloss, k: int = 5, method: str = "cie76") -> SnapResult:
        """ColorSnap the design's Lab at 15/45/110° against the whole library."""
        lab = design.lab_at(np.array(SNAP_ANGLES))
        self.snap_result = color_snap(self.library, lab, k, method, self._index)
        self.events.snapped.emit(self.snap_result)
        return self.snap_result

    @lru_cache(maxsize=1024)  # noqa: B019 (one model per window; the cache dies with it)
    def design_of(self, i: int) -> FaceFlopTravelGloss:
        """Design of library row *i*."""
        return paint_design(self.library, i)

    @lru_cache(maxsize=1024)  # noqa: B019
    def thumbnail(self, i: int, size: int = 40) -> np.ndarray:
        """Rendered thumbnail of row *i*: its design on the bent booklet panel
        (``station.design.palette.booklet``), (size, size, 3) uint8."""
        return booklet(self.design_of(i), size)
