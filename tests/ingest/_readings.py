"""Deterministic synthetic readings for the ingest tests (client id and values derived from a seed)."""

from __future__ import annotations

import datetime as dt
import random
import uuid

from station.ingest import InstrumentRef, Reading

NAMESPACE = uuid.UUID("6f1d3c1e-8a8b-4b7e-9a55-2f0d7c1a0b01")
T0 = dt.datetime(2026, 11, 23, 6, 0, tzinfo=dt.UTC)


def make_reading(seed: int, index: int, serial: str = "SIM-MA-0001", panel_id: int | None = None) -> Reading:
    """Reading number *index* of the stream *seed* (same arguments, same reading, same hash)."""
    rng = random.Random(seed * 1_000_003 + index)
    face = [rng.uniform(40, 110), rng.uniform(-20, 20), rng.uniform(-30, 30)]
    return Reading(
        client_id=uuid.uuid5(NAMESPACE, f"{serial}/{seed}/{index}"),
        instrument=InstrumentRef(serial=serial, model="MA-98 simulator"),
        panel_id=panel_id,
        operator="kill-test",
        measured_at=T0 + dt.timedelta(seconds=index),
        geometries_deg=[15.0, 45.0, 110.0],
        lab=[
            face,
            [face[0] * 0.6, face[1] * 0.8, face[2] * 0.8],
            [face[0] * 0.3, face[1] * 0.5, face[2] * 0.5],
        ],
        wavelengths_nm=[400.0 + 10 * k for k in range(31)],
        spectra=[[rng.uniform(0, 1.5) for _ in range(31)] for _ in range(3)],
        gloss_gu=rng.uniform(60, 95),
    )
