"""Instrument session and stored measurements (Qt-free; the screen runs these calls in a worker thread).

A session connects to a device address or to a simulator (``sim:ma6`` / ``sim:ma3`` / ``sim:gloss``,
started as a subprocess by :func:`station.drivers.simproc.spawn_simulator`), calibrates and measures.
A gloss meter can be paired with the spectrophotometer, as the service's ``gloss_instrument_id`` does:
each scan then reads the gloss meter first (20/60/85° GU, haze, DOI), and its 60° gloss goes into the
record and the design fit. A gloss meter alone gives a gloss reading that is shown but not stored (a
stored measurement needs Lab per geometry).
Lab comes from ``station.model.spectra.reflectance_to_lab`` (D65/10°) and the design from
``station.model.fit_fftg`` on the in-plane 45° illumination block; the ingest record is the one
conversion ``station.ingest.record_from_reading``; each measurement is kept with its panel metadata
(job, part, substrate, notes) through a :class:`MeasurementStore`, whose sink stores it through
``station.ingest.Ingestor`` (``ui.models.measure_db``).
"""

from __future__ import annotations

import datetime as dt
from collections.abc import Callable
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from station.drivers import CalibrationResult, GlossReading, Instrument, open_instrument
from station.drivers.readings import SpectralReading
from station.drivers.simproc import SIM_KINDS, SimulatorProcess, spawn_simulator
from station.errors import InputError
from station.model import AspecularMeasurements, FaceFlopTravelGloss, fit_fftg
from station.model.design_io import design_to_dict
from station.model.domain import ILLUMINATION_DEG, geometry_name
from station.model.spectra import reflectance_to_lab
from ui.models.events import EventGroup
from ui.models.measure_db import MeasurementSink, PanelInfo

if TYPE_CHECKING:
    from station.ingest import Reading, Receipt

SIM_DEVICES = tuple(f"sim:{k}" for k in SIM_KINDS)
Progress = Callable[[int, str], None]
STEPS = 4


@dataclass(frozen=True)
class Measurement:
    """One scan: panel metadata, geometries, Lab per geometry, optional gloss and fitted design, and the
    ingest :class:`~station.ingest.Reading` (the 45° block; its client id keeps a re-sent scan single)."""

    panel: PanelInfo
    device: str
    time: str
    geometries: tuple[str, ...]
    aspecular_deg: tuple[int, ...]
    lab: np.ndarray = field(repr=False)
    spectra: np.ndarray = field(repr=False)
    gloss_gu: float | None = None
    design: FaceFlopTravelGloss | None = None
    note: str = ""
    reading: Reading | None = field(default=None, repr=False)
    receipt: Receipt | None = None
    gloss: GlossReading | None = None

    @property
    def gloss_only(self) -> bool:
        """A gloss meter's reading without colour (shown, never stored on its own)."""
        return self.gloss is not None and not self.geometries

    def gloss_text(self) -> str:
        """The gloss values as a line for the screen, or ``""`` without a gloss reading."""
        return gloss_summary(self.gloss) if self.gloss is not None else ""

    def to_dict(self) -> dict[str, Any]:
        """JSON-able record."""
        return {
            "panel": asdict(self.panel),
            "device": self.device,
            "time": self.time,
            "geometries": list(self.geometries),
            "lab": np.round(self.lab, 4).tolist(),
            "spectra": np.round(self.spectra, 5).tolist(),
            "gloss_gu": self.gloss_gu,
            "gloss": None if self.gloss is None else self.gloss.to_dict(),
            "note": self.note,
            "design": design_to_dict(self.design) if self.design is not None else None,
            "client_id": None if self.reading is None else str(self.reading.client_id),
        }


def ingest_record(reading: SpectralReading, gloss: GlossReading | None = None) -> Reading:
    """The ingest record of the scan's in-plane 45° illumination block (``station.ingest.record_from_reading``:
    Lab from the spectra through the model, D65/10°; 60° gloss of the paired meter; a fresh client id;
    ``$CACAD_OPERATOR`` or the login name as operator). Raises :class:`InputError` when the reading has
    no 45° illumination block."""
    from station.ingest import operator_name, record_from_reading

    return record_from_reading(reading, operator=operator_name("viewer"), illumination_deg=45, gloss=gloss)


def gloss_summary(g: GlossReading) -> str:
    """``gloss 20° … GU · 60° … GU · 85° … GU · haze … HU · DOI …`` (the meter's geometries, ISO 2813)."""
    gu = " · ".join(f"{k}° {v:.1f} GU" for k, v in sorted(g.gloss_gu.items()))
    return f"gloss {gu} · haze {g.haze_hu:.1f} HU · DOI {g.doi:.1f}"


def measurement_from_reading(
    reading: SpectralReading | GlossReading,
    panel: PanelInfo,
    device: str,
    gloss: GlossReading | None = None,
) -> Measurement:
    """Lab (model), and the FFTG fit of the 45° block's positive aspecular angles (eqs 3.3.1–3.3.10).

    *gloss* is the paired gloss meter's reading of the same panel: its 60° value (GU) enters the fit
    and the ingest record (``record_from_reading(gloss=...)``, as the service's measure route). A
    :class:`GlossReading` alone gives a measurement without colour whose gloss values are shown."""
    from station.ingest.records import GLOSS_GEOMETRY_DEG  # ingest loads SQLAlchemy: on first scan only

    now = dt.datetime.now(dt.UTC).isoformat(timespec="seconds")
    if isinstance(reading, GlossReading):
        g60 = reading.gloss_gu.get(GLOSS_GEOMETRY_DEG)
        return Measurement(
            panel,
            device,
            now,
            (),
            (),
            np.zeros((0, 3)),
            np.zeros((0, 31)),
            None if g60 is None else float(g60),
            None,
            "gloss meter alone: shown, not stored (pair it with a spectrophotometer to store gloss "
            "with the colour)",
            gloss=reading,
        )
    gloss_gu = None
    if gloss is not None:
        if GLOSS_GEOMETRY_DEG not in gloss.gloss_gu:
            raise InputError("gloss", "a gloss reading with a 60° geometry", sorted(gloss.gloss_gu))
        gloss_gu = float(gloss.gloss_gu[GLOSS_GEOMETRY_DEG])
    lab = np.asarray(reflectance_to_lab(reading.reflectance), float)
    angles, _rows = reading.block(45)
    keep = [i for i, a in enumerate(angles) if a > 0]
    design, note = None, ""
    if len(keep) >= 3:
        idx = [reading.geometries.index(geometry_name(ILLUMINATION_DEG, angles[i])) for i in keep]
        try:
            fit = fit_fftg(AspecularMeasurements(tuple(float(angles[i]) for i in keep), lab[idx], gloss_gu))
            design = fit.design
            note = f"fit residual ΔE max {max(fit.residual_de):.2f}"
        except InputError as exc:
            note = f"no design fit: {exc}"
    record: Reading | None = None
    try:
        record = ingest_record(reading, gloss)
    except (InputError, ValueError) as exc:  # kept on screen; the store refuses it with this note
        note = f"not stored: {exc}"
    return Measurement(
        panel,
        device,
        now,
        tuple(reading.geometries),
        tuple(reading.aspecular_deg),
        lab,
        np.asarray(reading.reflectance, float),
        gloss_gu,
        design,
        note,
        record,
        gloss=gloss,
    )


class MeasurementStore:
    """The scans made since the viewer started, in memory (the database is the record). Event: ``added(measurement)``.

    *sink* (a :class:`~ui.models.measure_db.MeasurementSink`) stores each scan; the screen calls
    :meth:`persist` in its worker thread and :meth:`add` in the GUI thread."""

    def __init__(self, sink: MeasurementSink | None = None) -> None:
        self.sink = sink
        self.items: list[Measurement] = []
        self.events = EventGroup("added")

    def persist(self, m: Measurement) -> Measurement:
        """Store *m* through the sink (queued on disk first); *m* with its receipt. Blocking."""
        if self.sink is None or m.gloss_only:
            return m
        if m.reading is None:
            from station.ingest import Receipt

            return replace(m, receipt=Receipt("", "refused", None, m.note))
        return replace(m, receipt=self.sink.submit(m.panel, m.reading))

    def add(self, m: Measurement) -> None:
        """Keep *m* and tell the listeners."""
        self.items.append(m)
        self.events.added.emit(m)


class _Link:
    """One open instrument and the simulator process behind it, if any."""

    def __init__(self) -> None:
        self.device = ""
        self.sim: SimulatorProcess | None = None
        self.instrument: Instrument | None = None

    def open(self, device: str, design_file: Path | None, timeout_s: float) -> str:
        self.close()
        device = device.strip()
        if not device:
            raise InputError("device", "sim:ma6 | sim:ma3 | sim:gloss or an address", device)
        address = device
        if device.startswith("sim:"):
            kind = device[4:]
            if kind not in SIM_KINDS:
                raise InputError("device", " | ".join(SIM_DEVICES) + " or an address", device)
            self.sim = spawn_simulator(kind, design_file)
            address = self.sim.address
        try:
            self.instrument = open_instrument(address, timeout_s=timeout_s)
        except Exception:
            self.close()
            raise
        self.device = device
        return address

    def close(self) -> None:
        if self.instrument is not None:
            try:
                self.instrument.close()
            finally:
                self.instrument = None
        if self.sim is not None:
            self.sim.close()
            self.sim = None
        self.device = ""


class InstrumentSession:
    """One connected instrument and an optional paired gloss meter (and their simulators). Blocking calls."""

    def __init__(self) -> None:
        self._main = _Link()
        self._gloss = _Link()

    @property
    def device(self) -> str:
        """The main device as typed (``""`` when none is connected)."""
        return self._main.device

    @property
    def instrument(self) -> Instrument | None:
        """The main instrument (a spectrophotometer or a gloss meter)."""
        return self._main.instrument

    @property
    def gloss_meter(self) -> Instrument | None:
        """The gloss meter paired with the spectrophotometer, if any."""
        return self._gloss.instrument

    @property
    def gloss_device(self) -> str:
        """The paired gloss meter as typed (``""`` when none)."""
        return self._gloss.device

    @property
    def connected(self) -> bool:
        """Whether an instrument is open."""
        return self._main.instrument is not None

    def connect(self, device: str, design_file: Path | None = None, timeout_s: float = 5.0) -> str:
        """Open *device* (``sim:KIND`` starts a simulator); returns the instrument's address."""
        return self._main.open(device, design_file, timeout_s)

    def pair_gloss(self, device: str, timeout_s: float = 5.0) -> str:
        """Open the gloss meter *device* (``sim:gloss`` starts a simulator) to read with every scan;
        returns its address. Refuses (:class:`InputError` naming ``gloss_device``) an instrument that is
        not a gloss meter, as the service's ``gloss_instrument_id``."""
        address = self._gloss.open(device, None, timeout_s)
        inst = self._gloss.instrument
        if inst is None or inst.kind != "gloss":
            self._gloss.close()
            raise InputError("gloss_device", "a gloss meter (e.g. sim:gloss)", device)
        return address

    def unpair_gloss(self) -> None:
        """Close the paired gloss meter."""
        self._gloss.close()

    def calibrate(self) -> list[tuple[str, CalibrationResult]]:
        """Run the calibration sequence of the instrument and of the paired gloss meter: (device, result)."""
        if self._main.instrument is None:
            raise InputError("instrument", "a connected instrument", None)
        out = [(self._main.device, self._main.instrument.calibrate())]
        if self._gloss.instrument is not None:
            out.append((self._gloss.device, self._gloss.instrument.calibrate()))
        return out

    def scan(
        self, panel: PanelInfo, progress: Progress | None = None, store: MeasurementStore | None = None
    ) -> Measurement:
        """Measure one panel. Progress (steps done of :data:`STEPS`, text): 0 measuring (the gloss meter
        first when paired), 1 measured, 2 Lab and fit done (storing); the screen shows :data:`STEPS` once the
        reading is shown. *progress* may raise (the user cancelled) at any step before storing."""
        inst = self._main.instrument
        if inst is None:
            raise InputError("instrument", "a connected instrument", None)
        panel = panel.validated()
        say = progress or (lambda _s, _t: None)
        gloss = None
        if self._gloss.instrument is not None and inst.kind != "gloss":
            say(0, f"reading the gloss meter {self._gloss.device}")
            reading = self._gloss.instrument.measure()
            if not isinstance(reading, GlossReading):
                raise InputError("gloss_device", "a gloss meter (e.g. sim:gloss)", self._gloss.device)
            gloss = reading
        say(0, f"measuring with {self._main.device}")
        spectral = inst.measure()
        say(1, "computing Lab and fitting the design")
        m = measurement_from_reading(spectral, panel, self.device, gloss)
        say(2, "storing" if store is not None and not m.gloss_only else "shown, not stored")
        if store is not None:  # the last step: not cancellable, a stored reading is always shown
            m = store.persist(m)
        return m

    def close(self) -> None:
        """Close the instruments and stop the simulators."""
        try:
            self._gloss.close()
        finally:
            self._main.close()
