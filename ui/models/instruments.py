"""Instrument session and stored measurements (Qt-free; the screen runs these calls in a worker thread).

A session connects to a device address or to a simulator (``sim:ma6`` / ``sim:ma3`` / ``sim:gloss``,
started as a subprocess by :func:`station.drivers.simproc.spawn_simulator`), calibrates and measures.
Lab comes from ``station.model.spectra.reflectance_to_lab`` (D65/10°) and the design from
``station.model.fit_fftg`` on the in-plane 45° illumination block; each measurement is kept with its
panel metadata in a :class:`MeasurementStore` (appended to a JSON-lines file when one is given).
"""

from __future__ import annotations

import datetime as dt
import json
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from station.drivers import GlossReading, open_instrument
from station.drivers.readings import SpectralReading
from station.drivers.simproc import SIM_KINDS, spawn_simulator
from station.errors import InputError
from station.model import AspecularMeasurements, FaceFlopTravelGloss, fit_fftg
from station.model.design_io import design_to_dict
from station.model.spectra import reflectance_to_lab
from ui.models.events import EventGroup

SIM_DEVICES = tuple(f"sim:{k}" for k in SIM_KINDS)
Progress = Callable[[int, str], None]
STEPS = 4


@dataclass(frozen=True)
class Measurement:
    """One stored reading: panel metadata, geometries, Lab per geometry, optional gloss and fitted design."""

    panel: str
    device: str
    time: str
    geometries: tuple[str, ...]
    aspecular_deg: tuple[int, ...]
    lab: np.ndarray = field(repr=False)
    spectra: np.ndarray = field(repr=False)
    gloss_gu: float | None = None
    design: FaceFlopTravelGloss | None = None
    note: str = ""

    def to_dict(self) -> dict[str, Any]:
        """JSON-able record."""
        return {"panel": self.panel, "device": self.device, "time": self.time, "geometries": list(self.geometries),
                "lab": np.round(self.lab, 4).tolist(), "spectra": np.round(self.spectra, 5).tolist(),
                "gloss_gu": self.gloss_gu, "note": self.note,
                "design": design_to_dict(self.design) if self.design is not None else None}


def measurement_from_reading(reading: SpectralReading | GlossReading, panel: str, device: str) -> Measurement:
    """Lab (model), and the FFTG fit of the 45° block's positive aspecular angles (eqs 3.3.1–3.3.10)."""
    now = dt.datetime.now(dt.UTC).isoformat(timespec="seconds")
    if isinstance(reading, GlossReading):
        g60 = reading.gloss_gu.get(60)
        return Measurement(panel, device, now, (), (), np.zeros((0, 3)), np.zeros((0, 31)),
                           None if g60 is None else float(g60), None, "gloss meter reading")
    lab = np.asarray(reflectance_to_lab(reading.reflectance), float)
    angles, _rows = reading.block(45)
    keep = [i for i, a in enumerate(angles) if a > 0]
    design, note = None, ""
    if len(keep) >= 3:
        idx = [reading.geometries.index(f"45as{angles[i]}") for i in keep]
        try:
            fit = fit_fftg(AspecularMeasurements(tuple(float(angles[i]) for i in keep), lab[idx], None))
            design = fit.design
            note = f"fit residual ΔE max {max(fit.residual_de):.2f}"
        except InputError as exc:
            note = f"no design fit: {exc}"
    return Measurement(panel, device, now, tuple(reading.geometries), tuple(reading.aspecular_deg), lab,
                       np.asarray(reading.reflectance, float), None, design, note)


class MeasurementStore:
    """Measurements in memory, appended to *path* (JSON lines) when given. Event: ``added(measurement)``."""

    def __init__(self, path: str | Path | None = None) -> None:
        self.path = Path(path) if path is not None else None
        self.items: list[Measurement] = []
        self.events = EventGroup("added")

    def add(self, m: Measurement) -> None:
        """Store *m* (written before the event fires: nothing is lost if a listener fails)."""
        if self.path is not None:
            with self.path.open("a", encoding="utf-8") as fh:
                fh.write(json.dumps(m.to_dict()) + "\n")
        self.items.append(m)
        self.events.added.emit(m)


class InstrumentSession:
    """One connected instrument (and the simulator process behind it, if any). Blocking calls."""

    def __init__(self) -> None:
        self.device = ""
        self._sim = None
        self.instrument = None

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

    def calibrate(self):
        """Run the instrument's calibration sequence (CalibrationResult)."""
        if self.instrument is None:
            raise InputError("instrument", "a connected instrument", None)
        return self.instrument.calibrate()

    def scan(self, panel: str, progress: Progress | None = None) -> Measurement:
        """Measure one panel: progress (step, text) for measure → Lab → fit → done."""
        if self.instrument is None:
            raise InputError("instrument", "a connected instrument", None)
        if not panel.strip():
            raise InputError("panel", "a non-empty panel id", panel)
        say = progress or (lambda _s, _t: None)
        say(1, "measuring")
        reading = self.instrument.measure()
        say(2, "computing Lab and fitting the design")
        m = measurement_from_reading(reading, panel.strip(), self.device)
        say(3, "done")
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
