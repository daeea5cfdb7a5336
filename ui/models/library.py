"""Library browser state (Qt-free): filter, hierarchy, ColorSnap of the current design, match designs,
and the booklet thumbnails of the paints a filter passes.

Everything numeric is the formulation core's: :class:`station.formulate.library.LibraryFilter`,
:func:`~station.formulate.library.hierarchy_counts`, :func:`station.formulate.snap.color_snap`; library
paints become designs with ``station.model.fit.fit_fftg_batch`` on their measured angles (many at once;
one paint fits exactly as with ``fit_fftg``), and thumbnails are ``station.design.palette.booklet``.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from station.design.palette import booklet
from station.errors import StationError
from station.formulate.library import Library, LibraryFilter, hierarchy_counts
from station.formulate.snap import SnapIndex, SnapResult, color_snap
from station.model import FaceFlopTravelGloss, FitResult
from station.model.display import lab_to_display
from station.model.domain import ANGLES_3
from station.model.errors import FitError
from station.model.fit import fit_fftg_batch
from ui.models.events import EventGroup

SNAP_ANGLES = ANGLES_3
#: Paints fitted and rendered per step of :meth:`LibraryModel.thumbnails` (one progress report each;
#: a step is also how long a stopped task takes to stop).
THUMB_CHUNK = 50
#: Edge of a library thumbnail, pixels.
THUMB_SIZE = 40


def paint_fits(library: Library, rows: Sequence[int]) -> list[FitResult | FitError]:
    """FFTG fits of library paints *rows* through their measured angles, in one batch (eqs 3.3.1–3.3.10):
    a :class:`FitResult` per paint, or the :class:`FitError` saying why it has none."""
    order = np.argsort(library.angles_deg)
    angles = tuple(float(library.angles_deg[j]) for j in order)
    idx = np.asarray(rows, dtype=int)
    batch = fit_fftg_batch(angles, library.lab[idx][:, order], library.gloss_gu[idx])
    out: list[FitResult | FitError] = []
    for n in range(len(batch)):
        try:
            out.append(batch.result(n))
        except FitError as exc:
            out.append(exc)
    return out


def paint_design(library: Library, i: int) -> FaceFlopTravelGloss:
    """FFTG fit of library paint *i* through its measured angles (raises :class:`FitError` if none)."""
    fit = paint_fits(library, [i])[0]
    if isinstance(fit, FitError):
        raise fit
    return fit.design


@dataclass(frozen=True)
class Thumbnail:
    """One library paint's thumbnail: the booklet image, or why the paint cannot be rendered."""

    row: int
    image: np.ndarray | None
    error: str | None = None


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
        self._fits: dict[int, FitResult | FitError] = {}
        self._thumbs: dict[tuple[int, int], np.ndarray] = {}
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

    def compute_snap(self, design: FaceFlopTravelGloss, k: int = 5, method: str = "cie76") -> SnapResult:
        """ColorSnap the design's Lab at 15/45/110° against the whole library, and fit the matches'
        designs (no event: safe off the GUI thread; :meth:`accept_snap` publishes the result)."""
        lab = design.lab_at(np.array(SNAP_ANGLES))
        result = color_snap(self.library, lab, k, method, self._index)
        self.fits([m.index for m in result.matches])
        return result

    def accept_snap(self, result: SnapResult) -> None:
        """Make *result* the current ColorSnap result (event ``snapped``)."""
        self.snap_result = result
        self.events.snapped.emit(result)

    def snap(self, design: FaceFlopTravelGloss, k: int = 5, method: str = "cie76") -> SnapResult:
        """:meth:`compute_snap` then :meth:`accept_snap`."""
        result = self.compute_snap(design, k, method)
        self.accept_snap(result)
        return result

    def fits(self, rows: Sequence[int]) -> list[FitResult | FitError]:
        """Fits of library rows *rows* (one batch for those not fitted before; cached)."""
        todo = sorted({int(r) for r in rows if int(r) not in self._fits})
        if todo:
            self._fits.update(zip(todo, paint_fits(self.library, todo), strict=True))
        return [self._fits[int(r)] for r in rows]

    def design_of(self, i: int) -> FaceFlopTravelGloss:
        """Design of library row *i* (raises :class:`FitError` when the paint has none)."""
        fit = self.fits([i])[0]
        if isinstance(fit, FitError):
            raise fit
        return fit.design

    def thumbnail(self, i: int, size: int = THUMB_SIZE) -> np.ndarray:
        """Rendered thumbnail of row *i*: its design on the bent booklet panel
        (``station.design.palette.booklet``), (size, size, 3) uint8 (cached)."""
        key = (int(i), int(size))
        if key not in self._thumbs:
            self._thumbs[key] = booklet(self.design_of(i), size)
        return self._thumbs[key]

    def thumbnails(
        self,
        rows: Sequence[int] | np.ndarray,
        on_chunk: Callable[[list[Thumbnail]], None],
        progress: Callable[[int, str], None] | None = None,
        size: int = THUMB_SIZE,
    ) -> int:
        """Thumbnails of *rows* in steps of :data:`THUMB_CHUNK`: each step fits its paints in one batch,
        renders them and hands the list to *on_chunk*, then reports ``progress(done, text)`` (which may
        raise to stop). A paint that cannot be fitted or rendered gets its reason instead of an image.
        Returns the number of thumbnails made."""
        done = 0
        for start in range(0, len(rows), THUMB_CHUNK):
            chunk = [int(r) for r in rows[start : start + THUMB_CHUNK]]
            out: list[Thumbnail] = []
            for r, fit in zip(chunk, self.fits(chunk), strict=True):
                if isinstance(fit, FitError):
                    out.append(Thumbnail(r, None, str(fit)))
                    continue
                try:
                    out.append(Thumbnail(r, self.thumbnail(r, size)))
                except StationError as exc:  # one paint that cannot be rendered never stops the list
                    out.append(Thumbnail(r, None, str(exc)))
            on_chunk(out)
            done += len(out)
            if progress is not None:
                progress(done, f"thumbnails {done} of {len(rows)}")
        return done
