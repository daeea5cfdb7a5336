"""Deterministic synthetic readings for the ingest tests (client id and values derived from a seed)."""

from __future__ import annotations

import datetime as dt
import random
import uuid

from station.ingest import InstrumentRef, Reading

NAMESPACE = uuid.UUID("6f1d3c1e-8a8b-4b7e-9a55-2f0d7c1a0b01")
T0 = dt.datetime(2026, 11, 23, 6, 0, tzinfo=dt.UTC)


def synthetic_reading(
    rng: random.Random,
    *,
    client_id: uuid.UUID,
    serial: str,
    operator: str,
    measured_at: dt.datetime,
    panel_id: int | None = None,
    spectra_decimals: int | None = None,
) -> Reading:
    """A three-angle reading (15°, 45°, 110°) drawn from *rng*: a face Lab, darker and duller at 45° and
    110°, 31-band spectra in 0..1.5 (rounded to *spectra_decimals* when given) and 60..95 GU of gloss."""
    face = [rng.uniform(40, 110), rng.uniform(-20, 20), rng.uniform(-30, 30)]

    def value() -> float:
        x = rng.uniform(0, 1.5)
        return x if spectra_decimals is None else round(x, spectra_decimals)

    return Reading(
        client_id=client_id,
        instrument=InstrumentRef(serial=serial, model="MA-98 simulator"),
        panel_id=panel_id,
        operator=operator,
        measured_at=measured_at,
        geometries_deg=[15.0, 45.0, 110.0],
        lab=[
            face,
            [face[0] * 0.6, face[1] * 0.8, face[2] * 0.8],
            [face[0] * 0.3, face[1] * 0.5, face[2] * 0.5],
        ],
        wavelengths_nm=[400.0 + 10 * k for k in range(31)],
        spectra=[[value() for _ in range(31)] for _ in range(3)],
        gloss_gu=rng.uniform(60, 95),
    )


def make_reading(seed: int, index: int, serial: str = "SIM-MA-0001", panel_id: int | None = None) -> Reading:
    """Reading number *index* of the stream *seed* (same arguments, same reading, same hash)."""
    return synthetic_reading(
        random.Random(seed * 1_000_003 + index),
        client_id=uuid.uuid5(NAMESPACE, f"{serial}/{seed}/{index}"),
        serial=serial,
        operator="kill-test",
        measured_at=T0 + dt.timedelta(seconds=index),
        panel_id=panel_id,
    )
