"""The canonical form of a chained row and its hashes (``db.chain``'s arithmetic, no database access).

A row's ``row_sha256`` is the SHA-256 of its canonical payload (the columns of :data:`PAYLOAD_COLUMNS`
as sorted-key JSON, UTC ISO timestamps with microseconds, numbers of float and JSON columns as floats);
its ``chain_sha256`` is SHA-256(previous link ‖ ``row_sha256``) (:func:`link_sha256`).

**Canonical numbers** (form 2, every row written from revision 0009 on): a number in a float or JSON
column is hashed as the shortest round-trip repr of the IEEE double (``json``'s), integers as floats,
and −0.0 as 0.0 (SQLite's REAL and PostgreSQL's JSONB both store −0.0 as 0). Rows written before
(``id <= ledger_heads.legacy_last_id``) were hashed with form 1, which kept the sign of zero: they
verify against form 2, form 1, or form 1 with the sign of some zeros restored (at most
:data:`LEGACY_ZERO_SIGNS` zeros, the signs the storage dropped; :func:`legacy_hashes`).
"""

from __future__ import annotations

import datetime as dt
import hashlib
import itertools
import json
import uuid
from collections.abc import Iterator, Mapping
from typing import Any, Literal

from station.model.domain import ILLUMINATION_DEG

Chain = Literal["measurements", "audit_events", "record_events"]
#: The JSON-typed payload columns; their numbers are hashed as floats (JSON number round-trips differ).
JSON_COLUMNS = frozenset({"geometries_deg", "lab", "wavelengths_nm", "spectra", "texture", "detail"})
#: Floating-point payload columns: hashed as floats whether the writer passed 60 or 60.0.
FLOAT_COLUMNS = frozenset({"gloss_gu", "gloss_geometry_deg", "illumination_deg"})
#: The most zeros of a form-1 row whose signs the audit tries to restore (2**n hashes).
LEGACY_ZERO_SIGNS = 10

PAYLOAD_COLUMNS: dict[Chain, tuple[str, ...]] = {
    "measurements": (
        "client_id",
        "panel_id",
        "instrument_id",
        "calibration_id",
        "operator",
        "measured_at",
        "received_at",
        "illuminant",
        "observer",
        "geometries_deg",
        "lab",
        "wavelengths_nm",
        "spectra",
        "gloss_gu",
        "gloss_geometry_deg",
        "payload_sha256",
        "supersedes_id",
        "correction_reason",
        "created_by_id",
    ),
    "audit_events": ("at", "actor_id", "action", "entity", "entity_id", "detail"),
    "record_events": ("at", "entity", "entity_id", "op", "state_sha256"),
}
#: Payload columns added after the chain: name → the value rows written before the column existed read.
#: A row's payload holds such a column only when its value differs from that value (a row without the
#: column, e.g. during revision 0004's back-fill, reads it too).
OPTIONAL_COLUMNS: dict[Chain, dict[str, Any]] = {
    "measurements": {"illumination_deg": ILLUMINATION_DEG, "texture": None},
    "audit_events": {},
    "record_events": {},
}


def _number(value: float, form: int) -> float:
    """A number as hashed: a float; form 2 also folds −0.0 into 0.0."""
    number = float(value)
    return 0.0 if form >= 2 and number == 0.0 else number


def _floats(value: Any, form: int = 2) -> Any:
    if isinstance(value, bool) or value is None or isinstance(value, str):
        return value
    if isinstance(value, (int, float)):
        return _number(value, form)
    if isinstance(value, Mapping):
        return {str(k): _floats(v, form) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_floats(v, form) for v in value]
    return value


def _scalar(value: Any) -> Any:
    if isinstance(value, dt.datetime):
        if value.tzinfo is None:
            value = value.replace(tzinfo=dt.UTC)
        return value.astimezone(dt.UTC).isoformat(timespec="microseconds")
    if isinstance(value, uuid.UUID):
        return str(value)
    if hasattr(value, "value") and not isinstance(value, (int, float, str)):  # an enum member
        return value.value
    return value


def _canonical(name: str, value: Any, form: int = 2) -> Any:
    return _floats(value, form) if name in JSON_COLUMNS or name in FLOAT_COLUMNS else _scalar(value)


def _digest(payload: Mapping[str, Any]) -> str:
    text = json.dumps(payload, sort_keys=True, separators=(",", ":"), ensure_ascii=True, allow_nan=False)
    return hashlib.sha256(text.encode("ascii")).hexdigest()


def _payload(chain: Chain, row: Mapping[Any, Any], form: int) -> dict[str, Any]:
    payload = {name: _canonical(name, row[name], form) for name in PAYLOAD_COLUMNS[chain]}
    for name, old in OPTIONAL_COLUMNS[chain].items():
        value = _canonical(name, row.get(name, old), form)
        if value != _canonical(name, old, form):
            payload[name] = value
    return payload


def payload_sha256(chain: Chain, row: Mapping[Any, Any], *, form: int = 2) -> str:
    """SHA-256 (hex) of the canonical payload of *row* (a mapping with every payload column).

    An optional column (:data:`OPTIONAL_COLUMNS`) enters the payload only when *row* holds it with a
    value other than its old-row value. *form* 1 is the form of rows written before revision 0009.
    """
    return _digest(_payload(chain, row, form))


def _zero_paths(value: Any, path: tuple[Any, ...] = ()) -> Iterator[tuple[Any, ...]]:
    if isinstance(value, float) and value == 0.0:
        yield path
    elif isinstance(value, dict):
        for k, v in value.items():
            yield from _zero_paths(v, (*path, k))
    elif isinstance(value, list):
        for i, v in enumerate(value):
            yield from _zero_paths(v, (*path, i))


def _negated(payload: Any, path: tuple[Any, ...]) -> Any:
    if not path:
        return -0.0
    head, rest = path[0], path[1:]
    if isinstance(payload, dict):
        return {k: (_negated(v, rest) if k == head else v) for k, v in payload.items()}
    return [(_negated(v, rest) if i == head else v) for i, v in enumerate(payload)]


def legacy_hashes(chain: Chain, row: Mapping[Any, Any]) -> Iterator[str]:
    """The form-1 hashes *row* may have been written with: as read, then with the sign of zeros restored.

    Form 1 hashed −0.0 as ``-0.0``; the storage returns 0.0, so the sign is tried back on every subset of
    the row's zeros (none when it holds more than :data:`LEGACY_ZERO_SIGNS`).
    """
    payload = _payload(chain, row, 1)
    yield _digest(payload)
    zeros = list(_zero_paths(payload))
    if len(zeros) > LEGACY_ZERO_SIGNS:
        return
    for size in range(1, len(zeros) + 1):
        for subset in itertools.combinations(zeros, size):
            signed: Any = payload
            for path in subset:
                signed = _negated(signed, path)
            yield _digest(signed)


def link_sha256(previous: str, row_sha256: str) -> str:
    """SHA-256 (hex) of the previous link followed by this row's payload hash (both hex)."""
    return hashlib.sha256((previous + row_sha256).encode("ascii")).hexdigest()
