"""Instruments attached to the service: connect, calibrate, measure."""

from __future__ import annotations

import datetime as dt
import uuid
from typing import Annotated, Literal

from pydantic import BaseModel, Field

from station.api.schemas.common import StrictInt
from station.api.schemas.measurements import MeasurementPublic
from station.drivers.families import SIM_FAMILY_NAMES
from station.schema_config import strict_config


class InstrumentPublic(BaseModel):
    """An attached instrument (``id`` is the service's handle, stable while it runs)."""

    id: str
    address: str
    model: str
    serial: str
    firmware: str
    kind: str
    simulated: bool
    geometries: list[str]
    calibration_needed: str | None
    calibration_id: str | None


class ConnectRequest(BaseModel):
    """The driver address of an instrument to attach (``family@where``, e.g. ``ma6@/dev/ttyUSB0``, or a
    simulator ``sim:ma6``); only the transports the product supports are accepted
    (``station.drivers.addresses``)."""

    model_config = strict_config(examples=[{"address": "ma6@/dev/ttyUSB0"}])

    address: Annotated[
        str,
        Field(
            min_length=3,
            max_length=255,
            pattern=r"^(sim:[a-z0-9]+|[a-z0-9_]+@[^\x00-\x1f\x7f]+)$",
            description=f"sim:{'|'.join(SIM_FAMILY_NAMES)}, FAMILY@/dev/ttyUSBn|/dev/ttyACMn|/dev/serial/by-id/NAME|COMn, "
            "FAMILY@socket://HOST:PORT or rfc2217://HOST:PORT (HOST in CACAD_INSTRUMENT_HOSTS), "
            "ma3@usb:VID:PID[:SERIAL], gloss@hid:VID:PID|/dev/hidrawN; anything else is refused",
        ),
    ]


class CalibrateRequest(BaseModel):
    """Which reference tile (or gloss standard) the calibration used."""

    model_config = strict_config(examples=[{"reference": "white tile W-17"}])

    reference: Annotated[str, Field(max_length=64, examples=["white tile W-17"])] = ""


class CalibrationPublic(BaseModel):
    """Outcome of a calibration (stored as a calibration record)."""

    record_id: int
    calibration_id: str
    steps: list[str]
    verification_de: float | None
    passed: bool
    expires: dt.datetime | None


class CalibrationStart(BaseModel):
    """Start a step-wise calibration of an attached spectrophotometer and, optionally, a gloss meter."""

    model_config = strict_config(
        examples=[{"instrument_id": "ma6-sim00001", "gloss_instrument_id": None, "reference": "W-17"}]
    )

    instrument_id: Annotated[str, Field(min_length=1, max_length=80, pattern=r"^[a-z0-9_.-]+$")]
    gloss_instrument_id: (
        Annotated[str, Field(min_length=1, max_length=80, pattern=r"^[a-z0-9_.-]+$")] | None
    ) = None
    reference: Annotated[str, Field(max_length=64, examples=["white tile W-17"])] = ""


class CalibrationStepOut(BaseModel):
    """One step of a calibration session: its place, device, the reference read and the prompt before it."""

    index: int
    total: int
    device: str
    step: str = Field(examples=["zero", "white", "verify", "gloss"])
    title: str = Field(examples=["White tile"])
    prompt: str
    status: Literal["pending", "running", "passed", "failed"]


class CalibrationSessionOut(BaseModel):
    """A step-wise calibration: its state, the step to prompt for next, every step, and once calibrated
    the stored records (one per instrument)."""

    id: uuid.UUID
    state: Literal["waiting", "running", "calibrated", "failed", "cancelled"]
    next: CalibrationStepOut | None = Field(
        description="the step to prompt for and run next (null once ended)"
    )
    steps: list[CalibrationStepOut]
    error: str | None = Field(description="why the session failed, naming the step")
    records: list[CalibrationPublic]
    calibrated: bool


class MeasureRequest(BaseModel):
    """Which panel the reading belongs to (optional), the illumination block to store and the client id.

    ``client_id`` (or the ``Idempotency-Key`` header) makes the request idempotent: a retry under the
    same id answers with what the first attempt stored or queued and measures nothing new.
    """

    model_config = strict_config(
        examples=[{"panel_id": 1, "client_id": "0f6b7c1e-2a3d-4e5f-8a9b-0c1d2e3f4a5b"}]
    )

    client_id: uuid.UUID | None = Field(None, description="idempotency key chosen by the client (a UUID)")
    panel_id: Annotated[StrictInt, Field(ge=1, le=2**31 - 1)] | None = None
    illumination_deg: Annotated[
        StrictInt, Field(ge=0, le=90, description="illumination angle of the stored block")
    ] = 45


class MeasureResult(BaseModel):
    """The stored measurement (``stored``; ``duplicate`` for a retry), or ``queued`` when the database was away."""

    status: Literal["stored", "duplicate", "queued"]
    client_id: uuid.UUID
    measurement: MeasurementPublic | None
    gloss_reading_id: int | None = Field(
        default=None, description="the full gloss reading stored with it when a gloss meter joined"
    )
