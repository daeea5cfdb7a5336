"""Routers, one per domain; ``ROUTERS`` are mounted under ``/api/v1``."""

from station.api.routes import (
    analyses,
    designs,
    health,
    instruments,
    library,
    measurements,
    panels,
    recipes,
    users,
)

ROUTERS = [
    instruments.router, panels.router, measurements.router, analyses.router, designs.router, library.router,
    recipes.router, users.router,
]

__all__ = ["ROUTERS", "health"]
