"""``station.wire``: a dataclass's wire form is :func:`dataclasses.asdict`'s JSON, with declared renames,
omissions, conversions and derived keys in their places."""

from __future__ import annotations

import datetime as dt
import json
from dataclasses import asdict, dataclass, field

import numpy as np
import pytest

from station.wire import iso_time, wire_form, wire_value


@dataclass(frozen=True)
class _Inner:
    name: str
    lab: tuple[float, float, float]


@dataclass(frozen=True)
class _Outer:
    sample: str
    inner: _Inner
    rows: tuple[tuple[float, ...], ...]
    recipe: dict[str, float]
    note: str | None = None
    parts: tuple[_Inner, ...] = field(default=())


@dataclass(frozen=True)
class _WithOwnForm:
    """A field whose class writes its own wire form."""

    value: float

    def to_dict(self) -> dict[str, str]:
        return {"shown": f"{self.value:.1f}"}


@dataclass(frozen=True)
class _Holder:
    item: _WithOwnForm
    items: tuple[_WithOwnForm, ...]
    lab: np.ndarray
    de: np.float64
    n: np.int64
    at: dt.datetime | None


def _outer() -> _Outer:
    return _Outer(
        "P1",
        _Inner("std", (50.0, 1.5, -2.0)),
        ((1.0, 2.0), (3.0, 4.0)),
        {"white": 0.25, "black": 0.75},
        parts=(_Inner("a", (1.0, 2.0, 3.0)), _Inner("b", (4.0, 5.0, 6.0))),
    )


def test_with_no_options_the_json_is_asdicts() -> None:
    x = _outer()
    assert json.dumps(wire_form(x)) == json.dumps(asdict(x))


def test_tuples_become_lists_at_every_depth() -> None:
    got = wire_form(_outer())
    assert got["rows"] == [[1.0, 2.0], [3.0, 4.0]] and isinstance(got["rows"][0], list)
    assert got["parts"][1] == {"name": "b", "lab": [4.0, 5.0, 6.0]}


def test_own_forms_numpy_and_times() -> None:
    when = dt.datetime(2026, 3, 1, 12, 30, tzinfo=dt.UTC)
    h = _Holder(
        _WithOwnForm(0.26),
        (_WithOwnForm(1.0),),
        np.array([[1.0, 2.0]]),
        np.float64(0.5),
        np.int64(3),
        when,
    )
    got = wire_form(h, convert={"at": iso_time})
    assert got == {
        "item": {"shown": "0.3"},
        "items": [{"shown": "1.0"}],
        "lab": [[1.0, 2.0]],
        "de": 0.5,
        "n": 3,
        "at": "2026-03-01T12:30:00+00:00",
    }
    assert type(got["de"]) is float and type(got["n"]) is int
    assert json.loads(json.dumps(got)) == got


def test_renames_omissions_and_derived_keys_keep_their_places() -> None:
    got = wire_form(
        _outer(),
        rename={"sample": "sample_id"},
        omit={"inner", "parts"},
        after={"sample": {"metric": "cie2000"}, "inner": {"std": "std"}, "parts": {"count": 2}},
    )
    assert list(got) == ["sample_id", "metric", "std", "rows", "recipe", "note", "count"]
    assert got["metric"] == "cie2000" and got["count"] == 2 and got["note"] is None


def test_a_misspelt_field_is_refused() -> None:
    with pytest.raises(ValueError, match="_Outer has no field smaple"):
        wire_form(_outer(), omit={"smaple"})


def test_plain_values_pass_through() -> None:
    assert wire_value(None) is None and wire_value("x") == "x" and wire_value(True) is True
    assert wire_value({"a": (1, 2)}) == {"a": [1, 2]}
    assert iso_time(None) is None
