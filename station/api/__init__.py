"""The workstation service (FastAPI): ``create_app(Settings(...))``; nothing is built at import.

The names load on first use (PEP 562): a command that only reads the settings or the users (``station
db``, ``station users``) does not import the application, which pulls in every router and the
colour-science stack (seconds of a command's start-up).
"""

from typing import TYPE_CHECKING

from station.lazy import lazy_getattr

if TYPE_CHECKING:
    from station.api.app import API_PREFIX, create_app
    from station.api.settings import Settings

_LAZY = {"station.api.app": ("API_PREFIX", "create_app"), "station.api.settings": ("Settings",)}

__getattr__ = lazy_getattr(__name__, _LAZY)

__all__ = ["API_PREFIX", "Settings", "create_app"]
