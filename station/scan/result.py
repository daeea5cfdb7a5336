"""The typed result of one scan: the readings taken, the records made of them and what became of them."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Literal

import numpy as np

from station.drivers import GlossReading, SpectralReading

if TYPE_CHECKING:  # SQLAlchemy and pydantic load with the first record, not with the viewer or the CLI
    from station.ingest import GlossRecord, Reading, Receipt

__all__ = ["GlossReceipt", "GlossStatus", "ScanResult"]

GlossStatus = Literal["stored", "duplicate", "not stored"]


@dataclass(frozen=True)
class GlossReceipt:
    """What happened to a gloss record: stored now, already stored under its client id, or not stored
    (*message* says why: the colour reading it joins is queued or refused, or the database is away)."""

    client_id: str
    status: GlossStatus
    gloss_reading_id: int | None = None
    message: str = ""


@dataclass(frozen=True)
class ScanResult:
    """One scan of one panel.

    *colour* is the spectrophotometer's reading (``None`` for a gloss meter alone), *gloss* the gloss
    meter's (the paired one, or the only instrument). *record* is the colour ingest record (the
    illumination block stored, with the 60° gloss of *gloss*), *gloss_record* the gloss meter's own record
    (a gloss-only reading on its panel, or naming the colour measurement once that is stored).
    *receipt* / *gloss_receipt* say what became of each once stored; *note* why a record is missing.
    """

    device: str
    colour: SpectralReading | None
    gloss: GlossReading | None
    record: Reading | None = field(default=None, repr=False)
    gloss_record: GlossRecord | None = field(default=None, repr=False)
    receipt: Receipt | None = None
    gloss_receipt: GlossReceipt | None = None
    note: str = ""

    @classmethod
    def of(
        cls, device: str, reading: SpectralReading | GlossReading, gloss: GlossReading | None = None
    ) -> ScanResult:
        """Readings taken already (by :func:`station.scan.take`, or built by a test) as a scan of *device*:
        a gloss meter's reading alone is gloss-only, a spectral one pairs with *gloss*."""
        if isinstance(reading, GlossReading):
            return cls(device, None, reading)
        return cls(device, reading, gloss)

    @property
    def gloss_only(self) -> bool:
        """A gloss meter's reading without colour (stored as a gloss reading of its own)."""
        return self.colour is None and self.gloss is not None

    @property
    def lab(self) -> np.ndarray:
        """CIE L*a*b* (D65, CIE 1964 10°) of every geometry, shape (n, 3), from the spectra through
        ``station.model.spectra.reflectance_to_lab`` (never the instrument's own Lab); (0, 3) without colour."""
        if self.colour is None:
            return np.zeros((0, 3))
        from station.model.spectra import reflectance_to_lab

        return np.asarray(reflectance_to_lab(self.colour.reflectance), float)

    @property
    def gloss_60_gu(self) -> float | None:
        """The 60° gloss (GU, ISO 2813) of the gloss reading, or ``None``."""
        if self.gloss is None:
            return None
        value = self.gloss.gloss_gu.get(60)
        return None if value is None else float(value)

    @property
    def client_id(self) -> str | None:
        """The client id of the reading stored first: the colour record's, else the gloss record's."""
        if self.record is not None:
            return str(self.record.client_id)
        if self.gloss_record is not None:
            return str(self.gloss_record.client_id)
        return None
