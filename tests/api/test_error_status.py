"""The HTTP status of each domain error family, as the docstring of ``station.api.errors`` states them: a
model, analysis, design or formulation error → 422, not found → 404, conflicts and an instrument needing
calibration → 409, an instrument or database that cannot be reached → 503, any other → 500."""

from __future__ import annotations

import pytest

from db.errors import DatabaseUnavailableError
from station.api.errors import NotFoundError, status_for
from station.drivers.errors import CalibrationNeeded, DriverError
from station.errors import StationError
from station.formulate.errors import NotFormulableError
from station.ingest.errors import ClientIdConflictError, ReferenceNotFoundError
from station.model.errors import FitError


@pytest.mark.parametrize(
    ("error", "status"),
    [
        (NotFormulableError("no recipe reaches the design"), 422),
        (FitError("the fit does not converge"), 422),
        (ReferenceNotFoundError("panel 7"), 404),
        (NotFoundError("user 7"), 404),
        (ClientIdConflictError("c-1", "aa", "bb"), 409),
        (CalibrationNeeded("white tile"), 409),
        (DriverError("no answer"), 503),
        (DatabaseUnavailableError("connection refused"), 503),
        (StationError("anything else"), 500),
    ],
    ids=lambda v: type(v).__name__ if isinstance(v, BaseException) else str(v),
)
def test_each_error_family_has_its_status(error: StationError, status: int) -> None:
    assert status_for(error) == status
