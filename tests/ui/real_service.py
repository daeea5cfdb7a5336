"""A real ``station serve`` (with the demo library) for the viewer's service-mode journeys, and one user
per role on it, created over HTTP by the bootstrap administrator as a person would."""

from __future__ import annotations

from collections.abc import Iterator, Mapping, Sequence
from contextlib import contextmanager
from pathlib import Path

import httpx

from tests.serve_process import serving

REPO = Path(__file__).resolve().parents[2]


@contextmanager
def station_service(tmp_path: Path, *roles: str) -> Iterator[tuple[str, dict[str, str]]]:
    """(base URL, {role: bearer token}) of a ``station serve`` of this checkout with its data in
    ``tmp_path/service`` (the demo library loaded on first start), stopped afterwards."""
    with serving(tmp_path / "service", cwd=REPO, start_timeout_s=180) as svc:
        admin = {"Authorization": f"Bearer {svc.token}"}
        tokens = {"admin": svc.token}
        with httpx.Client(base_url=svc.base, timeout=30.0) as client:
            for role in roles:
                r = client.post("/api/v1/users", json={"name": f"{role}-1", "role": role}, headers=admin)
                r.raise_for_status()
                tokens[role] = r.json()["token"]
        yield svc.base, tokens


def paint_csv(rows: list[tuple[str, str, float, Mapping[float, Sequence[float]]]]) -> str:
    """Library CSV (``station.formulate.library_csv``'s header) of (code, type, gloss GU, {angle: Lab})
    rows, every row at the same angles (15, 45, 110 first)."""
    angles = [15.0, 45.0, 110.0] + sorted(set(rows[0][3]) - {15.0, 45.0, 110.0})
    head = ["code", "type", "gloss_gu"] + [f"{c}{a:g}" for a in angles for c in "Lab"]
    lines = [",".join(head)]
    for code, kind, gloss, lab in rows:
        lines.append(",".join([code, kind, f"{gloss:g}"] + [f"{v:.4f}" for a in angles for v in lab[a]]))
    return "\n".join(lines) + "\n"
