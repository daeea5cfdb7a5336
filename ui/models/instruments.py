"""Instrument session and stored measurements (Qt-free; the screen runs these calls in a worker thread).

A session connects to a device address or to a simulator (``sim:ma6`` / ``sim:ma3`` / ``sim:gloss``,
started as a subprocess by :func:`station.drivers.simproc.spawn_simulator`), calibrates and measures.
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
            "note": self.note,
            "design": design_to_dict(self.design) if self.design is not None else None,
            "client_id": None if self.reading is None else str(self.reading.client_id),
        }


def ingest_record(reading: SpectralReading) -> Reading:
    """The ingest record of the scan's in-plane 45° illumination block (``station.ingest.record_from_reading``:
    Lab from the spectra through the model, D65/10°; a fresh client id; ``$CACAD_OPERATOR`` or the login
    name as operator). Raises :class:`InputError` when the reading has no 45° illumination block."""
    from station.ingest import operator_name, record_from_reading

    return record_from_reading(reading, operator=operator_name("viewer"), illumination_deg=45)


def measurement_from_reading(
    reading: SpectralReading | GlossReading, panel: PanelInfo, device: str
) -> Measurement:
    """Lab (model), and the FFTG fit of the 45° block's positive aspecular angles (eqs 3.3.1–3.3.10)."""
    now = dt.datetime.now(dt.UTC).isoformat(timespec="seconds")
    if isinstance(reading, GlossReading):
        g60 = reading.gloss_gu.get(60)
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
            "gloss meter reading (not stored: a measurement needs Lab per geometry)",
        )
    lab = np.asarray(reflectance_to_lab(reading.reflectance), float)
    angles, _rows = reading.block(45)
    keep = [i for i, a in enumerate(angles) if a > 0]
    design, note = None, ""
    if len(keep) >= 3:
        idx = [reading.geometries.index(geometry_name(ILLUMINATION_DEG, angles[i])) for i in keep]
        try:
            fit = fit_fftg(AspecularMeasurements(tuple(float(angles[i]) for i in keep), lab[idx], None))
            design = fit.design
            note = f"fit residual ΔE max {max(fit.residual_de):.2f}"
        except InputError as exc:
            note = f"no design fit: {exc}"
    record: Reading | None = None
    try:
        record = ingest_record(reading)
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
        None,
        design,
        note,
        record,
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
        if self.sink is None:
            return m
        if m.reading is None:
            from station.ingest import Receipt

            return replace(m, receipt=Receipt("", "refused", None, m.note))
        return replace(m, receipt=self.sink.submit(m.panel, m.reading))

    def add(self, m: Measurement) -> None:
        """Keep *m* and tell the listeners."""
        self.items.append(m)
        self.events.added.emit(m)


class InstrumentSession:
    """One connected instrument (and the simulator process behind it, if any). Blocking calls."""

    def __init__(self) -> None:
        self.device = ""
        self._sim: SimulatorProcess | None = None
        self.instrument: Instrument | None = None

    @property
    def connected(self) -> bool:
        """Whether an instrument is open."""
        return self.instrument is not None

    def connect(self, device: str, design_file: Path | None = None, timeout_s: float = 5.0) -> str:
        """Open *device* (``sim:KIND`` starts a simulator); returns the instrument's address."""
        self.close()
        device = device.strip()
        if not device:
            raise InputError("device", "sim:ma6 | sim:ma3 | sim:gloss or an address", device)
        address = device
        if device.startswith("sim:"):
            kind = device[4:]
            if kind not in SIM_KINDS:
                raise InputError("device", " | ".join(SIM_DEVICES) + " or an address", device)
            self._sim = spawn_simulator(kind, design_file)
            address = self._sim.address
        try:
            self.instrument = open_instrument(address, timeout_s=timeout_s)
        except Exception:
            self.close()
            raise
        self.device = device
        return address

    def calibrate(self) -> CalibrationResult:
        """Run the instrument's calibration sequence (CalibrationResult)."""
        if self.instrument is None:
            raise InputError("instrument", "a connected instrument", None)
        return self.instrument.calibrate()

    def scan(
        self, panel: PanelInfo, progress: Progress | None = None, store: MeasurementStore | None = None
    ) -> Measurement:
        """Measure one panel: progress (step, text) for measure → Lab and fit → store → done."""
        if self.instrument is None:
            raise InputError("instrument", "a connected instrument", None)
        panel = panel.validated()
        say = progress or (lambda _s, _t: None)
        say(1, "measuring")
        reading = self.instrument.measure()
        say(2, "computing Lab and fitting the design")
        m = measurement_from_reading(reading, panel, self.device)
        if store is not None:
            say(3, "storing")
            m = store.persist(m)
        return m

    def close(self) -> None:
        """Close the instrument and stop the simulator."""
        if self.instrument is not None:
            try:
                self.instrument.close()
            finally:
                self.instrument = None
        if self._sim is not None:
            self._sim.close()
            self._sim = None
        self.device = ""
