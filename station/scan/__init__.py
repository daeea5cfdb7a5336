"""The scan path: connect, calibrate, pair gloss with colour, store or queue, answer a retry.

Every front scans through this package: the viewer (``ui.models.instruments``), the service
(``station.api.instruments``) and the CLI (``station measure``). None of them pairs readings, builds
records or stores gloss rows itself (``tests/test_architecture.py`` fails when one does).

1. :func:`open_device` / :func:`open_gloss_meter` — an instrument (and its simulator for ``sim:KIND``);
   :class:`CalibrationSession` runs their calibration steps one at a time, each after its prompt
   (black trap, white tile, verification tile, gloss standard); :func:`calibrate` runs them all.
2. :func:`take` — the paired gloss meter first, then the spectrophotometer: a :class:`ScanResult`.
3. :func:`make_records` — the colour ingest record (with the 60° gloss) and the gloss meter's own record.
4. :func:`store` — through a :class:`ScanTarget`: colour via ``station.ingest.Ingestor`` (queued on disk
   while the database is away), gloss via ``station.ingest.store_gloss``; :func:`prior` answers a retry
   under the same client id from what the first attempt left.

A gloss meter alone gives a gloss-only reading: on every front it is stored as a gloss reading of its
own (``gloss_readings``) on its panel, which the QC views pair with a colour reading of that panel.
"""

from station.scan.calibration import (
    STEP_PROMPTS,
    CalibrationCancelled,
    CalibrationSession,
    CalibrationStep,
    CalibrationStepError,
    calibrate,
)
from station.scan.devices import SIM_DEVICES, Device, open_device, open_gloss_meter
from station.scan.errors import ScanError, ScanInputError
from station.scan.result import GlossReceipt, GlossStatus, ScanResult
from station.scan.store import DatabaseTarget, ScanTarget, prior, store
from station.scan.take import GLOSS_GEOMETRY_DEG, Progress, gloss_client_id, make_records, take

__all__ = [
    "GLOSS_GEOMETRY_DEG",
    "SIM_DEVICES",
    "STEP_PROMPTS",
    "CalibrationCancelled",
    "CalibrationSession",
    "CalibrationStep",
    "CalibrationStepError",
    "DatabaseTarget",
    "Device",
    "GlossReceipt",
    "GlossStatus",
    "Progress",
    "ScanError",
    "ScanInputError",
    "ScanResult",
    "ScanTarget",
    "calibrate",
    "gloss_client_id",
    "make_records",
    "open_device",
    "open_gloss_meter",
    "prior",
    "store",
    "take",
]
