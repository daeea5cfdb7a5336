"""Instruments attached to the service: simulators spawned at start, devices connected by address.

Driver calls block (serial I/O, polling), so routes run the hub's methods in a worker thread
(``asyncio.to_thread``); each instrument serialises its own calls with its lock. Instruments are opened,
measured, paired with a gloss meter, turned into records and stored through ``station.scan``, the scan
path the viewer and the CLI use too; this hub holds them open, keeps the audit and the calibration
records, and presents the result. A measurement is stored by the service's ``station.ingest.Ingestor``
(exactly once by client id); when the database is away it is kept in the on-disk outbox and replayed
before the next one and periodically. While the service knows the
database is away (:class:`~station.api.availability.DatabaseState`) a measurement goes straight to the
outbox without waiting on the database.
"""

from __future__ import annotations

import logging
import threading
import uuid
from dataclasses import asdict, dataclass

from sqlalchemy import Engine, select
from sqlalchemy.orm import Session, sessionmaker

from db.base import utcnow
from db.models import CalibrationRecord, Instrument, User
from station import scan
from station.api.availability import DatabaseState
from station.api.calibration_sessions import CalibrationSessions
from station.api.errors import ConflictError, NotFoundError, UnavailableError
from station.api.schemas.instruments import (
    CalibrationPublic,
    CalibrationSessionOut,
    InstrumentPublic,
    MeasureRequest,
    MeasureResult,
)
from station.api.services import audit
from station.api.services import measurements as measurement_service
from station.api.settings import Settings
from station.drivers import CalibrationResult, CommunicationError, split_address
from station.drivers import Instrument as Driver
from station.drivers.addresses import check_address
from station.drivers.families import SIM_FAMILY_NAMES
from station.drivers.readings import InstrumentInfo
from station.drivers.simproc import SimulatorProcess
from station.errors import InputError
from station.ingest import (
    ClientIdConflictError,
    DatabaseDestination,
    Ingestor,
    Outbox,
    Receipt,
    calibration_client_id,
)
from station.scan import ScanInputError

log = logging.getLogger(__name__)


class SimulatorLimitError(ConflictError):
    """The station runs ``max_simulators`` simulators already (409 naming the limit)."""

    def __init__(self, limit: int) -> None:
        self.limit = limit
        super().__init__(
            f"simulator limit reached: at most {limit} simulators run on this station (max_simulators, "
            "$CACAD_MAX_SIMULATORS); detach one first (DELETE /api/v1/instruments/{id})"
        )


@dataclass
class Attached:
    """One attached instrument and, for a simulator, the child process behind it."""

    id: str
    driver: Driver
    info: InstrumentInfo
    simulator: SimulatorProcess | None


class InstrumentHub:
    """The instruments this service holds open."""

    def __init__(
        self,
        *,
        settings: Settings,
        engine: Engine,
        sessions: sessionmaker[Session],
        database: DatabaseState | None = None,
    ) -> None:
        self.settings = settings
        self.engine = engine
        self.sessions = sessions
        self.database = database or DatabaseState()
        self._attached: dict[str, Attached] = {}
        self._spawning = 0  # simulator slots reserved by spawns under way (guarded by _lock)
        self._lock = threading.Lock()
        self._ingestor: Ingestor | None = None
        self._ingestor_lock = threading.Lock()
        self.calibrations = CalibrationSessions()

    # -- lifecycle ----------------------------------------------------------------------------------
    def attach_simulators(self, kinds: tuple[str, ...] | list[str]) -> None:
        """Spawn and attach one simulator per kind; a failure (the cap included) is logged, not fatal."""
        for kind in kinds:
            try:
                self._spawn_and_attach(kind)
            except Exception as exc:
                log.warning("simulator %s not attached: %s", kind, exc)

    def _reserve_simulator(self) -> None:
        """Take one of the ``max_simulators`` slots or raise :class:`SimulatorLimitError`."""
        limit = self.settings.max_simulators
        with self._lock:
            running = sum(a.simulator is not None for a in self._attached.values()) + self._spawning
            if running >= limit:
                raise SimulatorLimitError(limit)
            self._spawning += 1

    def _spawn_and_attach(self, kind: str) -> Attached:
        """Spawn simulator *kind* within the cap and attach it; the child is ended on any failure."""
        self._reserve_simulator()
        try:
            return self._attach(f"sim:{kind}")
        finally:
            with self._lock:
                self._spawning -= 1

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
        if self._ingestor is not None:
            self._ingestor.close()

    def _simulator_args(self, address: str) -> list[str]:
        """The simulator options of the settings for ``sim:KIND`` (none for a real address): ``--drift``
        and ``--state FOLDER/KIND.json`` (the folder made when missing)."""
        kind = address.strip().removeprefix("sim:")
        if not address.strip().startswith("sim:") or kind not in SIM_FAMILY_NAMES:
            return []  # open_device names a bad address
        out: list[str] = []
        if self.settings.simulator_drift is not None:
            out += ["--drift", repr(self.settings.simulator_drift)]
        if self.settings.simulator_state_dir is not None:
            self.settings.simulator_state_dir.mkdir(parents=True, exist_ok=True)
            out += ["--state", str((self.settings.simulator_state_dir / f"{kind}.json").resolve())]
        return out

    def _attach(self, address: str) -> Attached:
        """Open *address* through ``station.scan.open_device`` (``sim:KIND`` starts its simulator) and
        attach it under a fresh handle; the instrument and its simulator are closed on any failure."""
        device = scan.open_device(address, field="address", extra_args=self._simulator_args(address))
        try:
            info = device.instrument.identify()
        except BaseException:
            device.close()
            raise
        family, _ = split_address(device.address)
        with self._lock:
            base = f"{family}-{info.serial}".lower()
            ident, n = base, 1
            while ident in self._attached:
                n += 1
                ident = f"{base}-{n}"
            attached = Attached(ident, device.instrument, info, device.simulator)
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
        """Open the instrument at *address* and attach it (``sim:KIND`` starts a simulator for it).

        *address* must be one of the forms :func:`station.drivers.addresses.check_address` accepts
        (TCP only to the configured ``instrument_hosts``); anything else is a 422 on ``address``. A
        failure to open answers without the transport's own text, which may describe local files.
        """
        check_address(address, tcp_hosts=self.settings.instrument_hosts)
        with self._lock:
            if any(a.driver.address == address for a in self._attached.values()):
                raise ConflictError(f"{address} is already attached")
        try:
            if address.startswith("sim:"):
                attached = self._spawn_and_attach(address.removeprefix("sim:"))
            else:
                attached = self._attach(address)
        except CommunicationError as exc:
            log.warning("connect %s failed: %s", address, exc)
            raise NotFoundError(f"no instrument answers at {address}") from exc
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

    def detach(self, *, instrument_id: str, actor: User) -> None:
        """Close the attached instrument *instrument_id* and forget it; a simulator's process is ended.

        A call under way on the instrument finishes first (the driver's lock); the handle then names
        nothing (404) and the address may be connected again.
        """
        with self._lock:
            attached = self._attached.pop(instrument_id, None)
        if attached is None:
            raise NotFoundError(f"instrument {instrument_id!r} is not attached")
        try:
            attached.driver.close()
        except Exception as exc:  # a device already gone: its handle is dropped all the same
            log.warning("instrument %s did not close cleanly: %s", instrument_id, exc)
        finally:
            if attached.simulator is not None:
                attached.simulator.close()
        with self.sessions() as session:
            audit.record(
                session=session,
                actor=actor,
                action="instrument.detach",
                entity="instrument",
                entity_id=instrument_id,
                address=attached.driver.address,
            )
            session.commit()

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
        return self._store_calibration(a, a.driver.calibrate(), reference, actor)

    def start_calibration(
        self, *, instrument_id: str, gloss_instrument_id: str | None, reference: str
    ) -> CalibrationSessionOut:
        """A step-wise calibration session of *instrument_id* (a spectrophotometer) and, with
        *gloss_instrument_id*, the gloss meter after it (:mod:`station.api.calibration_sessions`)."""
        a = self._spectro(instrument_id)
        devices = [scan.Device(instrument_id, a.driver)]
        gloss = self._gloss_meter(gloss_instrument_id)
        if gloss is not None and gloss_instrument_id is not None:
            devices.append(scan.Device(gloss_instrument_id, gloss))
        return self.calibrations.start(devices, reference)

    def calibration_step(self, *, session_id: uuid.UUID, actor: User) -> CalibrationSessionOut:
        """Run the next step of session *session_id*; after the last, store a record per instrument."""

        def store(name: str, result: CalibrationResult, reference: str) -> CalibrationPublic:
            return self._store_calibration(self.get(name), result, reference, actor)

        return self.calibrations.step(session_id, store)

    def _store_calibration(
        self, a: Attached, result: CalibrationResult, reference: str, actor: User
    ) -> CalibrationPublic:
        """Store the calibration record of *result* once (by its calibration id) and audit it."""
        with self.sessions() as session:
            inst = self._instrument_row(session, a)
            client_id = calibration_client_id(a.info.serial, result.calibration_id)
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
                instrument=a.id,
                passed=result.passed,
            )
            session.commit()
            return CalibrationPublic(record_id=record.id, **asdict(result))

    def _spectro(self, instrument_id: str) -> Attached:
        """The attached spectrophotometer *instrument_id*: 404 when none is attached, 422 naming
        ``instrument_id`` for a gloss meter."""
        a = self.get(instrument_id)
        if a.driver.kind != "spectro":
            raise InputError(
                "instrument_id",
                "a spectrophotometer (gloss meters join via gloss_instrument_id)",
                instrument_id,
            )
        return a

    def _gloss_meter(self, gloss_id: str | None) -> Driver | None:
        """The attached gloss meter *gloss_id* to pair with a scan (``None`` without one)."""
        if gloss_id is None:
            return None
        driver = self.get(gloss_id).driver
        if driver.kind != "gloss":
            raise InputError("gloss_instrument_id", "an attached gloss meter with a 60° geometry", gloss_id)
        return driver

    def measure(
        self,
        *,
        instrument_id: str,
        req: MeasureRequest,
        gloss_instrument_id: str | None,
        actor: User,
        client_id: uuid.UUID | None = None,
    ) -> MeasureResult:
        """Measure once through ``station.scan`` and store it exactly once (queued on disk when the database is away).

        With *client_id* (the request's, or its ``Idempotency-Key``) a retry is answered from what the
        first attempt left: the stored measurement (``duplicate``) or the outbox entry (``queued``),
        without measuring again. A paired gloss meter's reading is stored as a gloss reading naming the
        measurement (``gloss_reading_id``) once the measurement is stored.
        """
        a = self._spectro(instrument_id)
        target = self.target()
        found = scan.prior(target, client_id, away=self.database.away)
        if isinstance(found, Receipt):
            return self._result(found)
        try:
            taken = scan.take(
                a.driver,
                self._gloss_meter(gloss_instrument_id),
                device=instrument_id,
                gloss_device=gloss_instrument_id or "",
                gloss_field="gloss_instrument_id",
            )
        except ScanInputError as exc:
            if exc.field == "instrument":
                raise InputError("instrument_id", "a spectrophotometer", instrument_id) from exc
            raise
        if taken.colour is None:  # a device that answered as a gloss meter: not stored as colour
            raise InputError("instrument_id", "a spectrophotometer", instrument_id)
        taken = scan.make_records(
            taken,
            operator=actor.name,
            illumination_deg=req.illumination_deg,
            client_id=client_id,
            instrument=a.info,
            panel_id=req.panel_id,
        )
        away = f"database away: {self.database.reason}" if self.database.away else None
        try:
            result = scan.store(taken, target, actor_id=actor.id, away=away)
        except ClientIdConflictError as exc:  # a concurrent request under the same key measured first
            raise ConflictError(str(exc)) from exc
        receipt = result.receipt
        if receipt is None:  # make_records raises rather than leave a colour reading without its record
            raise RuntimeError(f"reading of {instrument_id} has no record")
        if receipt.status == "queued":
            self.database.mark_away(receipt.message or "reading queued")
            log.warning(
                "database unreachable; reading %s queued in %s",
                receipt.client_id,
                target.ingestor.outbox.path,
            )
        gloss_id = None if result.gloss_receipt is None else result.gloss_receipt.gloss_reading_id
        return self._result(receipt).model_copy(update={"gloss_reading_id": gloss_id})

    def measure_gloss(
        self, *, instrument_id: str, panel_id: int | None, measurement_id: int | None, actor: User
    ) -> int:
        """Measure once on the gloss meter *instrument_id* through ``station.scan`` and store the gloss
        reading; its row id.

        The reading is gloss-only (with *panel_id*) or names the colour measurement it belongs to
        (*measurement_id*). It is stored directly, not through the outbox: while the database is away
        this is a 503 and nothing is measured.
        """
        a = self.get(instrument_id)
        if a.driver.kind != "gloss":
            raise InputError("instrument_id", "an attached gloss meter", instrument_id)
        if self.database.away:
            raise UnavailableError(f"database away: {self.database.reason}; gloss reading not taken")
        taken = scan.take(a.driver, device=instrument_id)
        if not taken.gloss_only:
            raise InputError("instrument_id", "an attached gloss meter", instrument_id)
        taken = scan.make_records(
            taken, operator=actor.name, panel_id=panel_id, measurement_id=measurement_id
        )
        receipt = scan.store(taken, self.target(), actor_id=actor.id).gloss_receipt
        if receipt is None or receipt.gloss_reading_id is None:  # store_gloss raises before this
            raise RuntimeError(f"gloss reading of {instrument_id} not stored")
        return receipt.gloss_reading_id

    def _result(self, receipt: Receipt) -> MeasureResult:
        client_id = uuid.UUID(receipt.client_id)
        if receipt.status == "refused":  # only an outbox-first ingestor reports a refusal; this one raises
            raise ConflictError(f"reading {receipt.client_id} refused: {receipt.message}")
        if receipt.measurement_id is None:
            return MeasureResult(status=receipt.status, client_id=client_id, measurement=None)
        with self.sessions() as session:
            stored = measurement_service.get_measurement(
                session=session, measurement_id=receipt.measurement_id
            )
        return MeasureResult(status=receipt.status, client_id=client_id, measurement=stored)

    def ingestor(self) -> Ingestor:
        """The service's ingest loop over its database and its outbox (opened on first use)."""
        with self._ingestor_lock:
            if self._ingestor is None:
                self._ingestor = Ingestor(
                    DatabaseDestination(
                        self.engine, action="measurement.create", replay_action="measurement.replay"
                    ),
                    self.settings.outbox_path,
                )
            return self._ingestor

    def target(self) -> scan.DatabaseTarget:
        """Where scans are stored: the service's ingestor (colour) and its database (gloss); a prior attempt
        that finds the database away marks it away."""
        return scan.DatabaseTarget(self.ingestor(), on_unreachable=self.database.mark_away)

    def outbox(self) -> Outbox:
        """The service's outbox (opened on first use)."""
        return self.ingestor().outbox

    def replay_outbox(self) -> int:
        """Store queued readings in order; stop when the database is still away."""
        if self._ingestor is None and not self.settings.outbox_path.exists():
            return 0
        return self.ingestor().replay()
