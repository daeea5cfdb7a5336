"""Routers, one per domain; ``ROUTERS`` are mounted under ``/api/v1``."""

from station.api.routes import designs, health, instruments, library, measurements, panels, recipes, users

ROUTERS = [
    instruments.router, panels.router, measurements.router, designs.router, library.router, recipes.router,
    users.router,
]

__all__ = ["ROUTERS", "health"]
