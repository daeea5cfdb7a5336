"""Client of the station service (``station viewer --service URL``): designs, the library and measurements.

The viewer computes everything with the local core; the service is where designs, the paint library and
measurements are shared. The token is the bearer token printed by ``station serve`` / ``station users add``
(``$STATION_TOKEN``). Routes: ``GET/POST /api/v1/designs`` (pages ``{"data": [...], "count"}``),
``GET /api/v1/library``; measurements go through :class:`ui.models.measure_db.ServiceSink`.
"""

from __future__ import annotations

import os
from typing import Any

import httpx
import numpy as np

from station.errors import StationError
from station.formulate.library import Library
from station.model import FaceFlopTravelGloss
from station.model.design_io import design_from_dict, design_to_dict

API = "/api/v1"


class ServiceError(StationError):
    """The service refused a request or could not be reached (the message says which and why)."""


def _detail(r: httpx.Response) -> str:
    """The service's own message of an error answer (its ``detail``), else the start of the body."""
    try:
        detail = r.json().get("detail")
    except (ValueError, AttributeError):
        detail = None
    if isinstance(detail, str):
        return detail
    if isinstance(detail, list) and detail and isinstance(detail[0], dict):  # 422: the first field named
        first = detail[0]
        return f"{'.'.join(str(x) for x in first.get('loc', ())[1:])}: {first.get('msg', '')}"
    return r.text[:300]


class ServiceUnreachable(ServiceError):
    """No HTTP answer at all (connection refused, timeout)."""


class ServiceClient:
    """Thin HTTP client; pass *client* (an ``httpx.Client``, e.g. FastAPI's TestClient) to reuse one."""

    def __init__(
        self, url: str, token: str | None = None, client: httpx.Client | None = None, timeout_s: float = 10.0
    ) -> None:
        self.url = url.rstrip("/")
        token = token if token is not None else os.environ.get("STATION_TOKEN", "")
        self._headers = {"Authorization": f"Bearer {token}"} if token else {}
        self._client = client or httpx.Client(base_url=self.url, timeout=timeout_s)
        self._own = client is None

    def request(self, method: str, path: str, **kw: Any) -> httpx.Response:
        """One request under ``/api/v1`` with the token; :class:`ServiceUnreachable` when nothing answers."""
        headers = {**self._headers, **kw.pop("headers", {})}
        try:
            return self._client.request(method, f"{API}{path}", headers=headers, **kw)
        except httpx.HTTPError as exc:
            raise ServiceUnreachable(f"service {self.url} unreachable: {exc}") from exc

    def checked(self, method: str, path: str, **kw: Any) -> httpx.Response:
        """:meth:`request`, and :class:`ServiceError` (status and the service's message) on HTTP >= 400."""
        r = self.request(method, path, **kw)
        if r.status_code >= 400:
            raise ServiceError(f"service {method} {path}: HTTP {r.status_code} {_detail(r)}")
        return r

    def call(self, method: str, path: str, **kw: Any) -> Any:
        """:meth:`checked`, returning the decoded JSON body."""
        return self.checked(method, path, **kw).json()

    def list_designs(self, limit: int = 100) -> list[tuple[int, str, FaceFlopTravelGloss]]:
        """(id, name, design) of the service's designs (first *limit*)."""
        page = self.call("GET", "/designs", params={"limit": limit})
        return [(int(d["id"]), str(d["name"]), design_from_dict(d["design"])) for d in page["data"]]

    def save_design(self, name: str, design: FaceFlopTravelGloss, note: str = "") -> int:
        """Store *design* as a new service design; returns its id."""
        body = {"name": name, "design": design_to_dict(design), "note": note}
        return int(self.call("POST", "/designs", json=body)["id"])

    def library(self, page: int = 1000) -> Library:
        """The service's paint library as a ``station.formulate.library.Library`` (every page).

        Paints whose angle set differs from the first paint's, or without gloss, are left out; the
        library's ``source`` says how many."""
        rows: list[dict[str, Any]] = []
        while True:
            got = self.call("GET", "/library", params={"limit": page, "offset": len(rows)})
            rows += got["data"]
            if not got["data"] or len(rows) >= int(got["count"]):
                break
        if not rows:
            raise ServiceError(f"service {self.url}: the library is empty")
        angles = tuple(float(a) for a in rows[0]["angles_deg"])
        keep = [
            r
            for r in rows
            if tuple(float(a) for a in r["angles_deg"]) == angles and r["gloss_gu"] is not None
        ]
        return Library(
            f"service {self.url}",
            np.array([r["code"] for r in keep]),
            np.array([r["category"] for r in keep]),
            np.array([float(r["gloss_gu"]) for r in keep]),
            angles,
            np.array([r["lab"] for r in keep], float).reshape(len(keep), len(angles), 3),
            source=f"{self.url}{API}/library ({len(rows) - len(keep)} of {len(rows)} paints left out: "
            "other angle set or no gloss)",
        )

    def close(self) -> None:
        """Close the HTTP client if this object made it."""
        if self._own:
            self._client.close()
