"""The light booth screen's model (Qt-free): standard and trial, the illuminant, the picture and the table.

Standard and trial come from the job history (the measurements of the workstation's database, newest
first, as ``station.qc.readings.reading_from_measurement`` reads them, or a service's measurements:
:class:`ServiceBoothSource`) or from a file
(``station.qc.readings.load_readings``: ``station measure --json`` / ``station import`` output, CxF3,
CGATS, the CSV template). Both need spectra. The illuminant is one of the booth's
(``station.model.illuminants.BOOTH_ILLUMINANTS``) or a user SPD file (``read_spd_file``); the observer
2° or 10°; the shape panels, seam or car (``station.model.booth.BOOTH_SHAPES``).

:meth:`BoothModel.compute` gives the picture (:class:`station.render.booth.BoothRenderer`, which keeps
each shape's basis images, so an illuminant switch is a refit and a weighted sum) and the per-geometry
rows of ``station.qc.booth.booth_compare`` under that illuminant: both Lab (the illuminant's own white),
ΔE00 and the special metamerism index from D65. Errors are StationError subclasses the screen shows.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol

import numpy as np

from station.errors import InputError, StationError

if TYPE_CHECKING:
    from station.model.illuminants import Illuminant
    from station.qc.readings import Reading
    from station.render.booth import BoothRenderer
    from ui.models.service import ServiceClient

#: The two sides of the booth.
ROLES = ("standard", "trial")
#: Observers offered ("10" is the product default).
OBSERVER_CHOICES = ("10", "2")
#: How many measurements of the history the pickers list.
HISTORY_LIMIT = 200


class BoothSourceError(StationError):
    """The job history could not be read (the database is away, a measurement is gone)."""


@dataclass(frozen=True)
class HistoryEntry:
    """One measurement of the job history: id, ``job part`` label, time, whether it has spectra."""

    id: int
    label: str
    measured_at: str
    has_spectra: bool

    @property
    def text(self) -> str:
        """The picker's line, e.g. ``#12 J-100 fender 2026-11-02T08:00:00`` (``no spectra`` when so)."""
        return f"#{self.id} {self.label} {self.measured_at}" + ("" if self.has_spectra else " (no spectra)")


class BoothSource(Protocol):
    """Where the booth reads the job history."""

    @property
    def where(self) -> str: ...
    def history(self, limit: int) -> list[HistoryEntry]: ...
    def reading(self, measurement_id: int) -> Reading: ...


class LocalBoothSource:
    """The workstation's database (as ``station serve``: ``$CACAD_DATABASE_URL`` or the default SQLite)."""

    def __init__(self, url: str | None = None) -> None:
        self._url = url
        self._sessions: Any = None

    @property
    def url(self) -> str:
        if self._url is None:
            from db.engine import configured_database_url

            self._url = configured_database_url()
        return self._url

    @property
    def where(self) -> str:
        return f"database {self.url}"

    def _session(self) -> Any:
        if self._sessions is None:
            from db.engine import make_engine, make_sessionmaker
            from db.migrate import ensure_at_head

            try:
                ensure_at_head(self.url)
            except Exception as exc:
                raise BoothSourceError(f"{self.where}: {type(exc).__name__}: {exc}") from exc
            self._sessions = make_sessionmaker(make_engine(self.url))
        return self._sessions()

    def history(self, limit: int = HISTORY_LIMIT) -> list[HistoryEntry]:
        """The newest *limit* measurements of the 45° illumination block, newest first."""
        from sqlalchemy import select

        from db.models import Measurement, Panel
        from station.model.domain import ILLUMINATION_DEG

        with self._session() as session:
            rows = session.execute(
                select(Measurement, Panel)
                .outerjoin(Panel, Panel.id == Measurement.panel_id)
                .where(Measurement.illumination_deg == ILLUMINATION_DEG)
                .order_by(Measurement.id.desc())
                .limit(limit)
            ).all()
            return [
                HistoryEntry(
                    int(m.id),
                    f"{p.job} {p.part}" if p is not None else "no panel",
                    _when(m.measured_at),
                    m.spectra is not None,
                )
                for m, p in rows
            ]

    def reading(self, measurement_id: int) -> Reading:
        """The stored measurement *measurement_id* as a reading (its spectra included)."""
        from db.models import Measurement
        from station.qc.readings import reading_from_measurement

        with self._session() as session:
            m = session.get(Measurement, measurement_id)
            if m is None:
                raise BoothSourceError(f"{self.where}: measurement {measurement_id} not found")
            return reading_from_measurement(m, sample=f"#{measurement_id}")


class ServiceBoothSource:
    """A station service: ``GET /api/v1/measurements`` (45° block, newest first), ``/panels`` for the
    labels, ``GET /api/v1/measurements/{id}`` for a reading with its spectra."""

    def __init__(self, client: ServiceClient) -> None:
        self.client = client

    @property
    def where(self) -> str:
        return f"service {self.client.url}"

    def _get(self, path: str, **params: Any) -> Any:
        from ui.models.service import ServiceUnreachable

        try:
            r = self.client.request("GET", path, params=params or None)
        except ServiceUnreachable as exc:
            raise BoothSourceError(f"{self.where}: {exc}") from exc
        if r.status_code >= 400:
            raise BoothSourceError(f"{self.where}: GET {path}: HTTP {r.status_code} {r.text[:300]}")
        return r.json()

    def history(self, limit: int = HISTORY_LIMIT) -> list[HistoryEntry]:
        """The newest *limit* measurements of the 45° illumination block, newest first."""
        from station.model.domain import ILLUMINATION_DEG

        rows = self._get("/measurements", limit=limit, illumination_deg=ILLUMINATION_DEG)["data"]
        panels = {int(p["id"]): p for p in self._get("/panels", limit=1000)["data"]}
        out = []
        for m in rows:
            p = panels.get(m.get("panel_id") or -1)
            label = f"{p['job']} {p['part']}" if p else "no panel"
            out.append(HistoryEntry(int(m["id"]), label, str(m["measured_at"]), m.get("spectra") is not None))
        return out

    def reading(self, measurement_id: int) -> Reading:
        """The stored measurement *measurement_id* as a reading (its spectra included)."""
        from station.qc.readings import Reading

        m = self._get(f"/measurements/{int(measurement_id)}")
        spectra = m.get("spectra")
        return Reading(
            tuple(float(a) for a in m["geometries_deg"]),
            tuple((float(r[0]), float(r[1]), float(r[2])) for r in m["lab"]),
            None if spectra is None else tuple(tuple(float(v) for v in r) for r in spectra),
            None if spectra is None else tuple(float(w) for w in m["wavelengths_nm"]),
            sample=f"#{measurement_id}",
            measurement_id=int(measurement_id),
            where=f"measurement {measurement_id}",
        )


def _when(value: Any) -> str:
    return value if isinstance(value, str) else value.isoformat(timespec="seconds")


@dataclass(frozen=True)
class BoothRow:
    """One geometry under the chosen illuminant: both Lab (its own white), ΔE00, metamerism index."""

    geometry: str
    standard_lab: tuple[float, float, float]
    trial_lab: tuple[float, float, float]
    de00: float
    metamerism_index: float


@dataclass(frozen=True)
class BoothView:
    """What the screen shows: the picture (H, W, 3) uint8, the rows, the illuminant's name, the mean ΔE00
    and the seconds the picture took (fits and weighted sum; the first one of a shape builds its images)."""

    image: np.ndarray
    rows: tuple[BoothRow, ...]
    illuminant: str
    mean_de: float
    seconds: float


class BoothModel:
    """State of the booth screen: the two readings, illuminant, observer, shape; computes the view."""

    def __init__(self, source: BoothSource | None, renderer: BoothRenderer | None = None) -> None:
        from station.render.booth import BoothRenderer

        self.source = source
        self.renderer = renderer if renderer is not None else BoothRenderer(isolate_gl=True)
        self.readings: dict[str, Reading | None] = dict.fromkeys(ROLES)
        self.labels: dict[str, str] = dict.fromkeys(ROLES, "")
        self.illuminant: str | Illuminant = "D65"
        self.observer = "10"
        self.shape = "panels"

    @property
    def illuminant_name(self) -> str:
        """The chosen illuminant's name (a user SPD's file stem)."""
        return self.illuminant if isinstance(self.illuminant, str) else self.illuminant.name

    @property
    def ready(self) -> bool:
        """Both standard and trial are chosen."""
        return all(self.readings[r] is not None for r in ROLES)

    def history(self, limit: int = HISTORY_LIMIT) -> list[HistoryEntry]:
        """The job history (BoothSourceError when there is no source or it cannot be read)."""
        if self.source is None:
            raise BoothSourceError("no measurement database: choose standard and trial from files")
        try:
            return self.source.history(limit)
        except StationError:
            raise
        except Exception as exc:  # a database driver's own error: say where and what
            raise BoothSourceError(f"{self.source.where}: {type(exc).__name__}: {exc}") from exc

    def _check_role(self, role: str) -> None:
        if role not in ROLES:
            raise InputError("role", " | ".join(ROLES), role)

    def _set(self, role: str, reading: Reading, label: str) -> str:
        from station.qc.booth import product_spectra

        product_spectra(reading, role)  # refuse a reading without spectra now, naming it
        self.readings[role] = reading
        self.labels[role] = label
        return label

    def pick_history(self, role: str, measurement_id: int) -> str:
        """Use the stored measurement *measurement_id* as *role*; returns its label."""
        self._check_role(role)
        if self.source is None:
            raise BoothSourceError("no measurement database")
        return self._set(role, self.source.reading(measurement_id), f"measurement #{measurement_id}")

    def pick_file(self, role: str, path: str | Path) -> str:
        """Use the one reading of file *path* as *role*; returns its label."""
        from station.qc.errors import QcInputError
        from station.qc.readings import load_readings

        self._check_role(role)
        readings = load_readings(path)
        if len(readings) != 1:
            raise QcInputError(f"{role} {Path(path).name}", "a file with one reading", len(readings))
        return self._set(role, readings[0], Path(path).name)

    def set_illuminant(self, name: str) -> str:
        """Choose a booth illuminant by name (any case; TL84 is F11's booth name); returns its name."""
        from station.model.illuminants import illuminant_name

        self.illuminant = illuminant_name(name)
        return self.illuminant

    def load_spd(self, path: str | Path) -> str:
        """Choose the illuminant of a user SPD file (``wavelength_nm,value`` rows, 400–700 nm)."""
        from station.model.illuminants import read_spd_file

        self.illuminant = read_spd_file(path)
        return self.illuminant.name

    def set_observer(self, observer: str) -> None:
        """``"10"`` or ``"2"``."""
        if observer not in OBSERVER_CHOICES:
            raise InputError("observer", " | ".join(OBSERVER_CHOICES), observer)
        self.observer = observer

    def set_shape(self, shape: str) -> None:
        """One of ``station.model.booth.BOOTH_SHAPES``."""
        from station.model.booth import check_booth_shape

        self.shape = check_booth_shape(shape)

    def compute(self) -> BoothView:
        """The picture and the per-geometry rows under the chosen illuminant (InputError when a side is
        missing or the readings do not fit together)."""
        from station.model.illuminants import observer_cie_name
        from station.qc.booth import booth_compare
        from station.render.booth import paint_from_reading

        standard, trial = self.readings["standard"], self.readings["trial"]
        if standard is None or trial is None:
            missing = [r for r in ROLES if self.readings[r] is None]
            raise InputError(missing[0], "a reading with spectra (job history or file)", None)
        observer = observer_cie_name(self.observer)
        comparison = booth_compare(standard, trial, [self.illuminant], observer).illuminants[0]
        frame = self.renderer.frame(
            paint_from_reading(standard, "standard"),
            paint_from_reading(trial, "trial"),
            self.illuminant,
            observer,
            self.shape,
        )
        rows = tuple(
            BoothRow(g.geometry, g.standard_lab, g.sample_lab, g.de00, g.metamerism_index)
            for g in comparison.per_geometry
        )
        return BoothView(frame.image, rows, comparison.name, comparison.mean_de, frame.seconds)
