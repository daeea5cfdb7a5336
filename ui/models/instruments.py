"""Instrument session and stored measurements (Qt-free; the screen runs these calls in a worker thread).

A session connects to a device address or to a simulator (``sim:ma6`` / ``sim:ma3`` / ``sim:gloss``),
pairs a gloss meter, calibrates and scans, all through :mod:`station.scan` (the one scan path the service
and the CLI use too): the paired gloss meter is read first (20/60/85° GU, haze, DOI) and its 60° gloss
goes into the colour record and the design fit; its full reading is stored as a gloss reading naming
the measurement. A gloss meter alone gives a gloss-only reading, stored as a gloss reading of its own on
the typed panel (as ``station measure sim:gloss --store`` and the service's ``/qc/gloss/measure``).
Lab comes from ``station.model.spectra.reflectance_to_lab`` (D65/10°) and the design from
``station.model.fit_fftg`` on the in-plane 45° illumination block; each measurement is kept with its
panel metadata (job, part, substrate, notes) through a :class:`MeasurementStore`, whose sink stores it
through ``station.ingest.Ingestor`` (``ui.models.measure_db``).
"""

from __future__ import annotations

import datetime as dt
from collections.abc import Sequence
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from station.drivers import CalibrationResult, GlossReading, Instrument
from station.drivers.readings import SpectralReading
from station.errors import InputError
from station.model import AspecularMeasurements, FaceFlopTravelGloss, fit_fftg
from station.model.design_io import design_to_dict
from station.model.domain import ILLUMINATION_DEG, geometry_name
from station.scan import (
    SIM_DEVICES,
    CalibrationSession,
    Device,
    GlossReceipt,
    Progress,
    ScanResult,
    make_records,
    open_device,
    open_gloss_meter,
    store,
    take,
)
from ui.models.events import EventGroup
from ui.models.measure_db import MeasurementSink, PanelInfo

if TYPE_CHECKING:
    from station.ingest import GlossRecord, Reading, Receipt

__all__ = ["SIM_DEVICES", "STEPS", "InstrumentSession", "Measurement", "MeasurementStore", "Progress"]

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
    gloss_record: GlossRecord | None = field(default=None, repr=False)
    gloss_receipt: GlossReceipt | None = None

    @property
    def gloss_only(self) -> bool:
        """A gloss meter's reading without colour (stored as a gloss reading of its own)."""
        return self.gloss is not None and not self.geometries

    @property
    def scan(self) -> ScanResult:
        """The records of this measurement as :func:`station.scan.store` takes them."""
        return ScanResult(self.device, None, self.gloss, self.reading, self.gloss_record)

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
    """The measurement of one scan (:func:`measurement_from_scan` of the readings as taken)."""
    return measurement_from_scan(ScanResult.of(device, reading, gloss), panel)


def measurement_from_scan(result: ScanResult, panel: PanelInfo) -> Measurement:
    """Lab (model), the FFTG fit of the 45° block's positive aspecular angles (eqs 3.3.1–3.3.10) with
    the paired meter's 60° gloss (GU), and the records of :func:`station.scan.make_records`. A gloss
    meter alone gives a measurement without colour whose gloss reading is stored on its own."""
    from station.ingest import operator_name  # ingest loads SQLAlchemy: on first scan only

    now = dt.datetime.now(dt.UTC).isoformat(timespec="seconds")
    result = make_records(result, operator=operator_name("viewer"), illumination_deg=45, refused="note")
    reading = result.colour
    if reading is None:
        return Measurement(
            panel,
            result.device,
            now,
            (),
            (),
            np.zeros((0, 3)),
            np.zeros((0, 31)),
            result.gloss_60_gu,
            None,
            result.note or "gloss meter alone: a gloss reading of the panel",
            gloss=result.gloss,
            gloss_record=result.gloss_record,
        )
    lab = result.lab
    angles, _rows = reading.block(45)
    keep = [i for i, a in enumerate(angles) if a > 0]
    design, note = None, ""
    if len(keep) >= 3:
        idx = [reading.geometries.index(geometry_name(ILLUMINATION_DEG, angles[i])) for i in keep]
        try:
            measured = AspecularMeasurements(
                tuple(float(angles[i]) for i in keep), lab[idx], result.gloss_60_gu
            )
            fit = fit_fftg(measured)
            design = fit.design
            note = f"fit residual ΔE max {max(fit.residual_de):.2f}"
        except InputError as exc:
            note = f"no design fit: {exc}"
    return Measurement(
        panel,
        result.device,
        now,
        tuple(reading.geometries),
        tuple(reading.aspecular_deg),
        lab,
        np.asarray(reading.reflectance, float),
        result.gloss_60_gu,
        design,
        result.note or note,  # a record refused is kept on screen; the store refuses it with this note
        result.record,
        gloss=result.gloss,
        gloss_record=result.gloss_record,
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
        """Store *m* through the sink with :func:`station.scan.store` (a colour reading queued on disk
        first; a gloss-only reading stored as a gloss reading); *m* with its receipts. Blocking.

        A gloss-only reading is not queued: while the store is away its receipt says ``not stored``."""
        if self.sink is None:
            return m
        if m.reading is None and m.gloss_record is None:
            from station.ingest import Receipt

            return replace(m, receipt=Receipt("", "refused", None, m.note))
        try:
            result = store(m.scan, _PanelTarget(self.sink, m.panel))
        except Exception as exc:
            from station.ingest import is_unreachable

            if m.gloss_record is None or m.reading is not None or not is_unreachable(exc):
                raise
            why = f"{self.sink.where} unreachable: {exc}"
            return replace(
                m, gloss_receipt=GlossReceipt(str(m.gloss_record.client_id), "not stored", None, why)
            )
        return replace(
            m, receipt=result.receipt, gloss_record=result.gloss_record, gloss_receipt=result.gloss_receipt
        )

    def add(self, m: Measurement) -> None:
        """Keep *m* and tell the listeners."""
        self.items.append(m)
        self.events.added.emit(m)


class _PanelTarget:
    """The :class:`station.scan.ScanTarget` of one scan: the sink, with the panel metadata typed for it."""

    def __init__(self, sink: MeasurementSink, panel: PanelInfo) -> None:
        self.sink = sink
        self.panel = panel

    @property
    def where(self) -> str:
        return self.sink.where

    def submit(self, reading: Reading, *, actor_id: int | None = None) -> Receipt:
        return self.sink.submit(self.panel, reading)

    def enqueue(self, reading: Reading, reason: str) -> Receipt:
        return self.sink.submit(self.panel, reading)  # the viewer's ingest queues every reading first

    def submit_gloss(self, record: GlossRecord, *, actor_id: int | None = None) -> GlossReceipt:
        return self.sink.submit_gloss(self.panel, record)


class InstrumentSession:
    """One connected instrument and an optional paired gloss meter (and their simulators). Blocking calls."""

    def __init__(self) -> None:
        self._main: Device | None = None
        self._gloss: Device | None = None

    @property
    def device(self) -> str:
        """The main device as typed (``""`` when none is connected)."""
        return "" if self._main is None else self._main.name

    @property
    def instrument(self) -> Instrument[Any] | None:
        """The main instrument (a spectrophotometer or a gloss meter)."""
        return None if self._main is None else self._main.instrument

    @property
    def gloss_meter(self) -> Instrument[Any] | None:
        """The gloss meter paired with the spectrophotometer, if any."""
        return None if self._gloss is None else self._gloss.instrument

    @property
    def gloss_device(self) -> str:
        """The paired gloss meter as typed (``""`` when none)."""
        return "" if self._gloss is None else self._gloss.name

    @property
    def connected(self) -> bool:
        """Whether an instrument is open."""
        return self._main is not None

    def connect(
        self,
        device: str,
        design_file: Path | None = None,
        timeout_s: float = 5.0,
        faults: Sequence[str] = (),
    ) -> str:
        """Open *device* (``sim:KIND`` starts a simulator, with *faults* armed); returns its address."""
        self._close_main()
        self._main = open_device(device, timeout_s=timeout_s, design_file=design_file, faults=faults)
        return self._main.address

    def pair_gloss(self, device: str, timeout_s: float = 5.0) -> str:
        """Open the gloss meter *device* (``sim:gloss`` starts a simulator) to read with every scan;
        returns its address. Refuses (:class:`InputError` naming ``gloss_device``) an instrument that is
        not a gloss meter, as the service's ``gloss_instrument_id``."""
        self.unpair_gloss()
        self._gloss = open_gloss_meter(device, timeout_s=timeout_s)
        return self._gloss.address

    def unpair_gloss(self) -> None:
        """Close the paired gloss meter."""
        gloss, self._gloss = self._gloss, None
        if gloss is not None:
            gloss.close()

    def calibration(self) -> CalibrationSession:
        """The calibration steps of the instrument and of the paired gloss meter, to run one at a time,
        each after its prompt (black trap, white tile, verification tile, gloss standard)."""
        if self._main is None:
            raise InputError("instrument", "a connected instrument", None)
        return CalibrationSession(self._main, self._gloss)

    def calibrate(self) -> list[tuple[str, CalibrationResult]]:
        """Run every calibration step without prompting: (device, result) per instrument."""
        return self.calibration().run_all()

    def scan(
        self, panel: PanelInfo, progress: Progress | None = None, store: MeasurementStore | None = None
    ) -> Measurement:
        """Measure one panel through :func:`station.scan.take`. Progress (steps done of :data:`STEPS`,
        text): 0 measuring (the gloss meter first when paired), 1 measured, 2 Lab and fit done (storing);
        the screen shows :data:`STEPS` once the reading is shown. *progress* may raise (the user
        cancelled) at any step before storing."""
        if self._main is None:
            raise InputError("instrument", "a connected instrument", None)
        panel = panel.validated()
        say = progress or (lambda _s, _t: None)
        taken = take(
            self._main.instrument,
            self.gloss_meter,
            device=self.device,
            gloss_device=self.gloss_device,
            progress=lambda s, t: say(s, "computing Lab and fitting the design" if s == 1 else t),
        )
        m = measurement_from_scan(taken, panel)
        say(2, "storing" if store is not None else "shown, not stored")
        if store is not None:  # the last step: not cancellable, a stored reading is always shown
            m = store.persist(m)
        return m

    def _close_main(self) -> None:
        main, self._main = self._main, None
        if main is not None:
            main.close()

    def close(self) -> None:
        """Close the instruments and stop the simulators."""
        try:
            self.unpair_gloss()
        finally:
            self._close_main()
