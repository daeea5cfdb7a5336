"""A service a test needs (an OpenGL context, the PostgreSQL server, a display) that is missing.

On a developer's machine the test skips with the reason; under ``CI=true`` (set by CI services) it
fails, so a CI machine without the service can never pass by skipping what it was meant to check.
"""

from __future__ import annotations

import os
from typing import NoReturn

import pytest


def under_ci() -> bool:
    """True when ``$CI`` is ``true`` (any case), as CI services set it."""
    return os.environ.get("CI", "").strip().lower() == "true"


def service_missing(reason: str) -> NoReturn:
    """Skip the running test for *reason*, or fail it under ``CI=true``."""
    if under_ci():
        pytest.fail(f"{reason} (CI=true: a missing service fails the run)", pytrace=False)
    pytest.skip(reason)
