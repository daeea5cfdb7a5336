"""Routers, one per domain; ``ROUTERS`` are mounted under ``/api/v1``."""

from station.api.routes import (
    analyses,
    booth,
    designs,
    formulation,
    health,
    instruments,
    library,
    measurements,
    panels,
    qc,
    recipes,
    styling,
    users,
)

ROUTERS = [
    instruments.router,
    panels.router,
    measurements.router,
    qc.router,
    booth.router,
    analyses.router,
    designs.router,
    library.router,
    styling.router,
    recipes.router,
    formulation.router,
    users.router,
]

__all__ = ["ROUTERS", "health"]
