"""Instruments attached to the service: simulators spawned at start, devices connected by address.

Driver calls block (serial I/O, polling), so routes run the hub's methods in a worker thread
(``asyncio.to_thread``); each instrument serialises its own calls with its lock. A measurement goes
through the same exactly-once path as any station reading; when the database is away it is kept in
the on-disk outbox and replayed before the next one.
"""

from __future__ import annotations

import logging
import threading
import uuid
from dataclasses import dataclass

import numpy as np
from sqlalchemy import select
from sqlalchemy.orm import Session, sessionmaker

from db.base import utcnow
from db.models import CalibrationRecord, Instrument, User
from station.api.errors import ConflictError, NotFoundError
from station.api.schemas.instruments import (
    CalibrationPublic,
    InstrumentPublic,
    MeasureRequest,
    MeasureResult,
)
from station.api.services import audit
from station.api.services import measurements as measurement_service
from station.api.settings import Settings
from station.drivers import CommunicationError, GlossReading, SpectralReading, open_instrument, split_address
from station.drivers import Instrument as Driver
from station.drivers.readings import InstrumentInfo
from station.drivers.simproc import SimulatorProcess, spawn_simulator
from station.errors import InputError
from station.ingest import CalibrationRef, InstrumentRef, Outbox, Reading, is_unreachable, store_reading
from station.model.spectra import reflectance_to_lab

log = logging.getLogger(__name__)

_CAL_NAMESPACE = uuid.UUID("0b9e8c1e-5d0c-4c7b-8f5e-2b7c3f1d9a11")


def calibration_uuid(serial: str, calibration_id: str) -> uuid.UUID:
    """A stable client id for an instrument's calibration (same device id → same record)."""
    return uuid.uuid5(_CAL_NAMESPACE, f"{serial}/{calibration_id}")


@dataclass
class Attached:
    """One attached instrument and, for a simulator, the child process behind it."""

    id: str
    driver: Driver
    info: InstrumentInfo
    simulator: SimulatorProcess | None


class InstrumentHub:
    """The instruments this service holds open."""

    def __init__(self, *, settings: Settings, sessions: sessionmaker[Session]) -> None:
        self.settings = settings
        self.sessions = sessions
        self._attached: dict[str, Attached] = {}
        self._lock = threading.Lock()
        self._outbox: Outbox | None = None
        self._outbox_lock = threading.Lock()

    # -- lifecycle ----------------------------------------------------------------------------------
    def attach_simulators(self, kinds: tuple[str, ...] | list[str]) -> None:
        """Spawn and attach one simulator per kind; a failure is logged, not fatal."""
        for kind in kinds:
            sim = None
            try:
                sim = spawn_simulator(kind)
                self._attach(sim.address, sim)
            except Exception as exc:
                log.warning("simulator %s not attached: %s", kind, exc)
                if sim is not None:
                    sim.close()

    def close(self) -> None:
        """Close every instrument and stop every simulator."""
        with self._lock:
            attached, self._attached = list(self._attached.values()), {}
        for a in attached:
            try:
                a.driver.close()
            finally:
                if a.simulator is not None:
                    a.simulator.close()
        if self._outbox is not None:
            self._outbox.close()

    def _attach(self, address: str, simulator: SimulatorProcess | None) -> Attached:
        family, _ = split_address(address)
        driver = open_instrument(address)
        try:
            info = driver.identify()
        except BaseException:
            driver.close()
            raise
        with self._lock:
            base = f"{family}-{info.serial}".lower()
            ident, n = base, 1
            while ident in self._attached:
                n += 1
                ident = f"{base}-{n}"
            attached = Attached(ident, driver, info, simulator)
            self._attached[ident] = attached
        return attached

    # -- queries ------------------------------------------------------------------------------------
    def get(self, instrument_id: str) -> Attached:
        """The attached instrument *instrument_id* or :class:`NotFoundError`."""
        with self._lock:
            attached = self._attached.get(instrument_id)
        if attached is None:
            raise NotFoundError(f"instrument {instrument_id!r} is not attached")
        return attached

    def _public(self, a: Attached) -> InstrumentPublic:
        needed: str | None = None
        cal_id: str | None = None
        try:
            st = a.driver.status()
            needed, cal_id = st.needed, st.calibration_id or None
        except Exception as exc:  # a device that does not answer still lists
            needed = f"unknown ({type(exc).__name__})"
        return InstrumentPublic(
            id=a.id,
            address=a.driver.address,
            model=a.info.model,
            serial=a.info.serial,
            firmware=a.info.firmware,
            kind=a.driver.kind,
            simulated=a.simulator is not None,
            geometries=list(a.info.geometries),
            calibration_needed=needed,
            calibration_id=cal_id,
        )

    def list(self) -> list[InstrumentPublic]:
        """Every attached instrument with its calibration state."""
        with self._lock:
            attached = list(self._attached.values())
        return [self._public(a) for a in attached]

    # -- operations ---------------------------------------------------------------------------------
    def connect(self, *, address: str, actor: User) -> InstrumentPublic:
        """Open the instrument at *address* and attach it."""
        with self._lock:
            if any(a.driver.address == address for a in self._attached.values()):
                raise ConflictError(f"{address} is already attached")
        try:
            attached = self._attach(address, None)
        except CommunicationError as exc:
            raise NotFoundError(f"no instrument answers at {address}: {exc}") from exc
        with self.sessions() as session:
            audit.record(
                session=session,
                actor=actor,
                action="instrument.connect",
                entity="instrument",
                entity_id=attached.id,
                address=address,
            )
            session.commit()
        return self._public(attached)

    def _instrument_row(self, session: Session, a: Attached) -> Instrument:
        row = session.scalar(select(Instrument).where(Instrument.serial == a.info.serial))
        if row is None:
            row = Instrument(
                serial=a.info.serial,
                model=a.info.model,
                kind="multiangle" if a.driver.kind == "spectro" else a.driver.kind,
                firmware=a.info.firmware,
                address=a.driver.address,
            )
            session.add(row)
            session.flush()
        return row

    def calibrate(self, *, instrument_id: str, reference: str, actor: User) -> CalibrationPublic:
        """Run the instrument's calibration sequence and store the record."""
        a = self.get(instrument_id)
        result = a.driver.calibrate()
        with self.sessions() as session:
            inst = self._instrument_row(session, a)
            client_id = calibration_uuid(a.info.serial, result.calibration_id)
            record = session.scalar(select(CalibrationRecord).where(CalibrationRecord.client_id == client_id))
            if record is None:
                record = CalibrationRecord(
                    client_id=client_id,
                    instrument_id=inst.id,
                    performed_at=utcnow(),
                    operator=actor.name,
                    reference=reference,
                    passed=result.passed,
                    result={
                        "calibration_id": result.calibration_id,
                        "steps": list(result.steps),
                        "verification_de": result.verification_de,
                        "expires": result.expires.isoformat() if result.expires else None,
                    },
                )
                session.add(record)
                session.flush()
            audit.record(
                session=session,
                actor=actor,
                action="instrument.calibrate",
                entity="calibration",
                entity_id=record.id,
                instrument=instrument_id,
                passed=result.passed,
            )
            session.commit()
            return CalibrationPublic(
                record_id=record.id,
                calibration_id=result.calibration_id,
                steps=list(result.steps),
                verification_de=result.verification_de,
                passed=result.passed,
                expires=result.expires,
            )

    def _gloss(self, gloss_id: str | None) -> tuple[float | None, int | None]:
        if gloss_id is None:
            return None, None
        reading = self.get(gloss_id).driver.measure()
        if not isinstance(reading, GlossReading) or 60 not in reading.gloss_gu:
            raise InputError("gloss_instrument_id", "an attached gloss meter with a 60° geometry", gloss_id)
        return float(reading.gloss_gu[60]), 60

    def reading_from(
        self,
        a: Attached,
        spectral: SpectralReading,
        req: MeasureRequest,
        operator: str,
        gloss: tuple[float | None, int | None],
    ) -> Reading:
        """The ingest reading for one illumination block of a spectral reading (Lab from the spectra)."""
        angles, refl = spectral.block(req.illumination_deg)
        if not angles:
            illum = sorted({int(g.split("as")[0]) for g in spectral.geometries})
            raise InputError("illumination_deg", f"one of {illum}", req.illumination_deg)
        lab = np.asarray(reflectance_to_lab(np.asarray(refl, dtype=float)))
        cal = None
        if spectral.calibration_id:
            cal = CalibrationRef(
                client_id=calibration_uuid(spectral.serial, spectral.calibration_id),
                performed_at=spectral.time,
                reference="",
            )
        return Reading(
            client_id=uuid.uuid4(),
            instrument=InstrumentRef(
                serial=spectral.serial or a.info.serial,
                model=a.info.model,
                kind="multiangle",
                firmware=a.info.firmware or None,
            ),
            calibration=cal,
            panel_id=req.panel_id,
            operator=operator,
            measured_at=spectral.time,
            geometries_deg=[float(x) for x in angles],
            lab=lab.round(4).tolist(),
            wavelengths_nm=[float(w) for w in spectral.wavelengths_nm],
            spectra=np.asarray(refl, dtype=float).round(6).tolist(),
            gloss_gu=gloss[0],
            gloss_geometry_deg=gloss[1],
        )

    def measure(
        self, *, instrument_id: str, req: MeasureRequest, gloss_instrument_id: str | None, actor: User
    ) -> MeasureResult:
        """Measure once, store it exactly once (or queue it on disk when the database is away)."""
        a = self.get(instrument_id)
        if a.driver.kind != "spectro":
            raise InputError(
                "instrument_id",
                "a spectrophotometer (gloss meters join via gloss_instrument_id)",
                instrument_id,
            )
        gloss = self._gloss(gloss_instrument_id)
        spectral = a.driver.measure()
        reading = self.reading_from(a, spectral, req, actor.name, gloss)
        self.replay_outbox()
        try:
            with self.sessions() as session:
                stored, _created = measurement_service.ingest(session=session, actor=actor, reading=reading)
        except Exception as exc:
            if not is_unreachable(exc):
                raise
            with self._outbox_lock:
                self.outbox().put(str(reading.client_id), reading.canonical_json())
            log.warning(
                "database unreachable; reading %s queued in %s", reading.client_id, self.outbox().path
            )
            return MeasureResult(status="queued", measurement=None)
        return MeasureResult(status="stored", measurement=stored)

    def outbox(self) -> Outbox:
        """The service's outbox (opened on first use)."""
        if self._outbox is None:
            self._outbox = Outbox(self.settings.outbox_path)
        return self._outbox

    def replay_outbox(self) -> int:
        """Store queued readings in order; stop when the database is still away."""
        if self._outbox is None and not self.settings.outbox_path.exists():
            return 0
        with self._outbox_lock:
            return self._replay(self.outbox())

    def _replay(self, box: Outbox) -> int:
        done = 0
        for entry in box.entries():
            try:
                with self.sessions.begin() as session:
                    reading = Reading.model_validate_json(entry.body)
                    result = store_reading(session, reading)
                    if result.created:
                        audit.record(
                            session=session,
                            actor=None,
                            action="measurement.replay",
                            entity="measurement",
                            entity_id=result.measurement_id,
                            client_id=str(reading.client_id),
                        )
            except Exception as exc:
                if is_unreachable(exc):
                    break
                box.bury(entry, str(exc))
            else:
                box.remove(entry.seq)
            done += 1
        return done
