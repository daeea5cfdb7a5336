"""Lab-only readings built through the product's import path, for tests that write measurement files.

:func:`lab_reading` is what a vendor file's reader would build for one sample: one row per geometry, the
given Lab values, no spectra, D65 and the 10° observer, an MA-T6-style instrument.
"""

from __future__ import annotations

from collections.abc import Sequence

from station.ingest.errors import ImportFileError
from station.ingest.formats import build_measurement
from station.ingest.formats.measurement import OBSERVERS, ImportedMeasurement, Instrument


def generated_error(fld: str, accepted: str, got: object) -> ImportFileError:
    """The error a generated reading raises for a bad field (no file or line to name)."""
    return ImportFileError("generated", "", fld, accepted, got)


def lab_reading(
    sample: str, geometries: Sequence[str], lab: Sequence[Sequence[float]], serial: str = "SN-7"
) -> ImportedMeasurement:
    """A reading of *sample*: *lab* (one L*, a*, b* row per geometry of *geometries*) on MA-T6 *serial*."""
    return build_measurement(
        sample=sample,
        rows=[(g, generated_error) for g in geometries],
        lab=lab,
        wavelengths_nm=None,
        spectra=None,
        instrument=Instrument("MA-T6", serial),
        illuminant="D65",
        observer=OBSERVERS[1],
        measured_at=None,
        err=generated_error,
    )
