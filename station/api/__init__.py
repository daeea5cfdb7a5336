"""The workstation service (FastAPI): ``create_app(Settings(...))``; nothing is built at import."""

from station.api.app import API_PREFIX, create_app
from station.api.settings import Settings

__all__ = ["API_PREFIX", "Settings", "create_app"]
