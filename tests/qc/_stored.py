"""A stored job for the tests of SPC and drift: one instrument, one fender panel per reading, a day apart."""

from __future__ import annotations

import datetime as dt
import uuid
from collections.abc import Sequence

from db.engine import make_engine, make_sessionmaker
from db.migrate import ensure_at_head
from db.models import Panel
from station.ingest import InstrumentRef, Reading, TextureValue, store_reading

ANGLES = [15.0, 45.0, 110.0]
#: The standard's Lab (D65/10°) at each of :data:`ANGLES`.
STD = [[92.0, -1.0, 2.0], [60.0, -0.5, 1.0], [35.0, 0.0, 0.5]]
#: A drifting series: ΔL* of each sample against the standard (= its ΔE*ab at every geometry), ten stable,
#: then eight creeping up to 1.03.
DL = [
    0.30,
    0.34,
    0.28,
    0.33,
    0.31,
    0.27,
    0.32,
    0.35,
    0.29,
    0.31,
    0.36,
    0.44,
    0.52,
    0.61,
    0.70,
    0.80,
    0.91,
    1.03,
]
#: When the first panel of a stored job was measured; each next one a day later.
T0 = dt.datetime(2026, 11, 2, 8, 0, tzinfo=dt.UTC)

Texture = list[dict[str, object]]


def store_job(
    url: str,
    job: str,
    labs: Sequence[list[list[float]]],
    textures: Sequence[Texture] | None = None,
    *,
    angles: Sequence[float] = ANGLES,
) -> list[int]:
    """Migrate the SQLite database at *url* to head and store job *job* in it through the one writer
    (:func:`station.ingest.store_reading`): one MA6 instrument and, for each entry of *labs* (Lab per
    geometry of *angles*, degrees), a fender panel measured ``T0 + i`` days, with the texture rows of the
    same entry of *textures* where given. Returns the measurements' ids, in order."""
    if textures is not None and len(textures) != len(labs):
        raise ValueError(f"textures: expected one per reading ({len(labs)}), got {len(textures)}")
    ensure_at_head(url)
    engine = make_engine(url)
    instrument = InstrumentRef(serial="600123", model="MA6", kind="spectrophotometer")
    ids = []
    with make_sessionmaker(engine)() as s:
        for i, lab in enumerate(labs):
            panel = Panel(job=job, part="fender")
            s.add(panel)
            s.flush()
            reading = Reading(
                client_id=uuid.uuid4(),
                instrument=instrument,
                panel_id=panel.id,
                operator="ana",
                measured_at=T0 + dt.timedelta(days=i),
                geometries_deg=list(angles),
                lab=lab,
                texture=None if textures is None else [TextureValue.model_validate(t) for t in textures[i]],
            )
            ids.append(store_reading(s, reading).measurement_id)
        s.commit()
    engine.dispose()
    return ids
