"""Client of the station service (``station viewer --service URL``): designs in and out over HTTP.

The viewer computes everything with the local core; the service is where designs are shared. The token
is the bearer token printed by ``station serve`` / ``station users add`` (``$STATION_TOKEN``).
Routes: ``GET /api/v1/designs`` (a page ``{"data": [...], "count"}``), ``POST /api/v1/designs``.
"""

from __future__ import annotations

import os
from typing import Any

import httpx

from station.errors import StationError
from station.model import FaceFlopTravelGloss
from station.model.design_io import design_from_dict, design_to_dict

API = "/api/v1"


class ServiceError(StationError):
    """The service refused a request or could not be reached (the message says which and why)."""


class ServiceClient:
    """Thin HTTP client; pass *client* (an ``httpx.Client``, e.g. FastAPI's TestClient) to reuse one."""

    def __init__(self, url: str, token: str | None = None, client: httpx.Client | None = None,
                 timeout_s: float = 10.0) -> None:
        self.url = url.rstrip("/")
        token = token if token is not None else os.environ.get("STATION_TOKEN", "")
        self._headers = {"Authorization": f"Bearer {token}"} if token else {}
        self._client = client or httpx.Client(base_url=self.url, timeout=timeout_s)
        self._own = client is None

    def _call(self, method: str, path: str, **kw: Any) -> Any:
        try:
            r = self._client.request(method, f"{API}{path}", headers=self._headers, **kw)
        except httpx.HTTPError as exc:
            raise ServiceError(f"service {self.url} unreachable: {exc}") from exc
        if r.status_code >= 400:
            raise ServiceError(f"service {method} {path}: HTTP {r.status_code} {r.text[:300]}")
        return r.json()

    def list_designs(self, limit: int = 100) -> list[tuple[int, str, FaceFlopTravelGloss]]:
        """(id, name, design) of the service's designs (first *limit*)."""
        page = self._call("GET", "/designs", params={"limit": limit})
        return [(int(d["id"]), str(d["name"]), design_from_dict(d["design"])) for d in page["data"]]

    def save_design(self, name: str, design: FaceFlopTravelGloss, note: str = "") -> int:
        """Store *design* as a new service design; returns its id."""
        body = {"name": name, "design": design_to_dict(design), "note": note}
        return int(self._call("POST", "/designs", json=body)["id"])

    def close(self) -> None:
        """Close the HTTP client if this object made it."""
        if self._own:
            self._client.close()
