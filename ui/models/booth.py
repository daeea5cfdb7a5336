"""The light booth screen's model (Qt-free): standard and trial, the illuminant, the picture and the table.

Standard and trial come from the job history (the measurements of the workstation's database, newest
first, as ``station.qc.readings.reading_from_measurement`` reads them, or a service's measurements:
:class:`ServiceBoothSource`) or from a file
(``station.qc.readings.load_readings``: ``station measure --json`` / ``station import`` output, CxF3,
CGATS, the CSV template). Both need spectra. Either side may instead be a recipe: a recipe JSON file
(``station formulate --json`` output, recognised by content) or a stored formulation job (the workstation's
database or a service's ``GET /api/v1/recipes``), predicted by the colorant model at the other side's
geometries (``station.qc.booth.booth_sides``). The illuminant is one of the booth's
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
from typing import TYPE_CHECKING, Any, Protocol, runtime_checkable

import numpy as np

from station.errors import InputError, StationError
from ui.models.local_db import LocalDatabase

if TYPE_CHECKING:
    from station.model.illuminants import Illuminant
    from station.qc.booth import BoothGeometry, BoothRecipe
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


@dataclass(frozen=True)
class RecipeJobEntry:
    """One stored formulation job: id, design and version, state, whether it holds a recipe."""

    id: int
    design_id: int
    version: int
    state: str
    has_recipe: bool

    @property
    def text(self) -> str:
        """The picker's line, e.g. ``recipe #4 design 2 v1 done`` (``no recipe`` when so)."""
        return f"recipe #{self.id} design {self.design_id} v{self.version} {self.state}" + (
            "" if self.has_recipe else " (no recipe)"
        )


@runtime_checkable
class RecipeJobSource(Protocol):
    """Where the booth reads the stored formulation jobs (a source may have none)."""

    def recipe_jobs(self, limit: int) -> list[RecipeJobEntry]: ...
    def recipe(self, recipe_id: int) -> BoothRecipe: ...


def _job_recipe(recipe_id: int, recipe: Any, where: str) -> BoothRecipe:
    from station.formulate.recipe_spectra import is_recipe_document, recipe_from_document
    from station.qc.booth import BoothRecipe

    doc = {"recipe": recipe} if not isinstance(recipe, dict) or "recipe" not in recipe else recipe
    if not is_recipe_document(doc):
        raise InputError(
            f"recipe {recipe_id}", "a formulation job with a recipe of the colorants", "no recipe"
        )
    return BoothRecipe(recipe_from_document(doc, f"recipe {recipe_id}"), f"recipe #{recipe_id} ({where})")


class BoothSource(Protocol):
    """Where the booth reads the job history."""

    @property
    def where(self) -> str: ...
    def history(self, limit: int) -> list[HistoryEntry]: ...
    def reading(self, measurement_id: int) -> Reading: ...


class LocalBoothSource(LocalDatabase):
    """The workstation's database (as ``station serve``: ``$CACAD_DATABASE_URL`` or the default SQLite)."""

    source_error = BoothSourceError

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

    def recipe_jobs(self, limit: int = HISTORY_LIMIT) -> list[RecipeJobEntry]:
        """The newest *limit* stored formulation jobs, newest first."""
        from sqlalchemy import select

        from db.models import DesignVersion, FormulationJob

        with self._session() as session:
            rows = session.execute(
                select(FormulationJob, DesignVersion.design_id, DesignVersion.version)
                .join(DesignVersion, DesignVersion.id == FormulationJob.design_version_id)
                .order_by(FormulationJob.id.desc())
                .limit(limit)
            ).all()
            return [
                RecipeJobEntry(int(j.id), int(d), int(v), str(j.state), bool((j.recipe or {}).get("recipe")))
                for j, d, v in rows
            ]

    def recipe(self, recipe_id: int) -> BoothRecipe:
        """The recipe of the stored formulation job *recipe_id*."""
        from db.models import FormulationJob

        with self._session() as session:
            job = session.get(FormulationJob, recipe_id)
            if job is None:
                raise BoothSourceError(f"{self.where}: recipe {recipe_id} not found")
            return _job_recipe(recipe_id, job.recipe, "database")


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

    def recipe_jobs(self, limit: int = HISTORY_LIMIT) -> list[RecipeJobEntry]:
        """The newest *limit* formulation jobs of ``GET /api/v1/recipes``, newest first."""
        rows = self._get("/recipes", limit=limit)["data"]
        return [
            RecipeJobEntry(
                int(r["id"]),
                int(r["design_id"]),
                int(r["design_version"]),
                str(r["state"]),
                bool(r.get("recipe")),
            )
            for r in rows
        ]

    def recipe(self, recipe_id: int) -> BoothRecipe:
        """The recipe of formulation job *recipe_id* (``GET /api/v1/recipes/{id}``)."""
        return _job_recipe(recipe_id, self._get(f"/recipes/{int(recipe_id)}").get("recipe"), "service")


def _when(value: Any) -> str:
    return value if isinstance(value, str) else value.isoformat(timespec="seconds")


@dataclass(frozen=True)
class BoothView:
    """What the screen shows: the picture (H, W, 3) uint8, the rows (the trial is each row's sample), the
    illuminant's name, the mean ΔE00 and the seconds the picture took (fits and weighted sum; the first one of a shape builds its images)."""

    image: np.ndarray
    rows: tuple[BoothGeometry, ...]
    illuminant: str
    mean_de: float
    seconds: float


class BoothModel:
    """State of the booth screen: the two readings, illuminant, observer, shape; computes the view."""

    def __init__(self, source: BoothSource | None, renderer: BoothRenderer | None = None) -> None:
        from station.render.booth import BoothRenderer

        self.source = source
        self.renderer = renderer if renderer is not None else BoothRenderer(isolate_gl=True)
        self.readings: dict[str, Reading | BoothRecipe | None] = dict.fromkeys(ROLES)
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

    def _set(self, role: str, reading: Reading | BoothRecipe, label: str) -> str:
        from station.qc.booth import BoothRecipe, product_spectra, recipe_reading

        if isinstance(reading, BoothRecipe):
            recipe_reading(reading, role=role)  # refuse an unknown colorant or a fraction out of bounds now
        else:
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
        """Use file *path* as *role*: one reading with spectra, or a recipe (recognised by content);
        returns its label."""
        from station.qc.booth import load_booth_side

        self._check_role(role)
        return self._set(role, load_booth_side(path, role), Path(path).name)

    def pick_recipe_file(self, role: str, path: str | Path) -> str:
        """Use the recipe of file *path* (``station formulate --json`` output) as *role*; returns its label."""
        from station.qc.booth import BoothRecipe, load_booth_side
        from station.qc.errors import QcInputError

        self._check_role(role)
        side = load_booth_side(path, role)
        if not isinstance(side, BoothRecipe):
            raise QcInputError(
                f"{role} {Path(path).name}", "a recipe (station formulate --json)", "a measurement"
            )
        return self._set(role, side, f"recipe {Path(path).name}")

    @property
    def has_recipe_jobs(self) -> bool:
        """Whether the source lists stored formulation jobs."""
        return isinstance(self.source, RecipeJobSource)

    def recipe_jobs(self, limit: int = HISTORY_LIMIT) -> list[RecipeJobEntry]:
        """The stored formulation jobs, newest first (BoothSourceError without a source that has them)."""
        if not isinstance(self.source, RecipeJobSource):
            raise BoothSourceError("no formulation jobs: choose a recipe file")
        try:
            return self.source.recipe_jobs(limit)
        except StationError:
            raise
        except Exception as exc:  # a database driver's own error: say where and what
            raise BoothSourceError(f"{type(exc).__name__}: {exc}") from exc

    def pick_recipe_job(self, role: str, recipe_id: int) -> str:
        """Use the recipe of stored formulation job *recipe_id* as *role*; returns its label."""
        self._check_role(role)
        if not isinstance(self.source, RecipeJobSource):
            raise BoothSourceError("no formulation jobs")
        return self._set(role, self.source.recipe(recipe_id), f"recipe #{recipe_id}")

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
        from station.qc.booth import booth_compare, booth_sides
        from station.render.booth import paint_from_reading

        std_side, trial_side = self.readings["standard"], self.readings["trial"]
        if std_side is None or trial_side is None:
            missing = [r for r in ROLES if self.readings[r] is None]
            raise InputError(missing[0], "a reading with spectra or a recipe (job history or file)", None)
        standard, trial = booth_sides(std_side, trial_side)
        observer = observer_cie_name(self.observer)
        comparison = booth_compare(standard, trial, [self.illuminant], observer).illuminants[0]
        frame = self.renderer.frame(
            paint_from_reading(standard, "standard"),
            paint_from_reading(trial, "trial"),
            self.illuminant,
            observer,
            self.shape,
        )
        return BoothView(
            frame.image, comparison.per_geometry, comparison.name, comparison.mean_de, frame.seconds
        )
