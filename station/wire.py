"""The wire form of a result: the JSON-able dict that ``--json``, the service and the files carry.

One rule for every dataclass's ``to_dict``: its fields in declaration order, each value made JSON-able the
same way (:func:`wire_value`), with what differs declared, never written out field by field::

    def to_dict(self) -> dict[str, object]:
        return wire_form(
            self,
            rename={"metamerism": "metamerism_index"},  # the field's key on the wire
            omit={"concentrations"},  # a field that stays off the wire
            convert={"measured_at": iso_time},  # a field's own conversion
            after={"tolerance": {"metric": "cie2000"}},  # derived keys, placed after that field
        )

With no options the form is :func:`dataclasses.asdict`'s, with tuples as lists and numpy values as Python
numbers: the same JSON.
"""

from __future__ import annotations

import dataclasses
import datetime as dt
from collections.abc import Callable, Collection, Mapping
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    from _typeshed import DataclassInstance

__all__ = ["iso_time", "wire_form", "wire_value"]


def wire_value(value: object) -> object:
    """*value* made JSON-able: an object with ``to_dict()`` as its own wire form, a dataclass as
    :func:`wire_form`, tuples and lists as lists and mappings as dicts (their items converted in turn), a
    numpy array as nested lists and a numpy scalar as the Python number; anything else (``None``, ``str``,
    ``int``, ``float``, ``bool``) as it is."""
    to_dict = getattr(value, "to_dict", None)
    if callable(to_dict):
        return to_dict()
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return wire_form(value)
    if isinstance(value, tuple | list):
        return [wire_value(v) for v in value]
    if isinstance(value, Mapping):
        return {k: wire_value(v) for k, v in value.items()}
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    return value


def iso_time(value: dt.datetime | None) -> str | None:
    """A time on the wire: ISO 8601 (``None`` stays ``None``)."""
    return None if value is None else value.isoformat()


def wire_form(
    obj: DataclassInstance,
    *,
    rename: Mapping[str, str] | None = None,
    omit: Collection[str] = (),
    convert: Mapping[str, Callable[[Any], object]] | None = None,
    after: Mapping[str, Mapping[str, object]] | None = None,
) -> dict[str, Any]:
    """The wire form of the dataclass *obj*: each field in declaration order as ``{key: value}``.

    Parameters
    ----------
    rename
        ``{field: key}``: the key a field goes under (default: its name).
    omit
        Fields left off the wire (a derived key in *after* may take their place).
    convert
        ``{field: function}``: the field's value on the wire is ``function(value)`` instead of
        :func:`wire_value`'s (e.g. a rounding or a time's ISO form).
    after
        ``{field: {key: value}}``: derived keys placed right after that field (or where it stands when it
        is omitted), each value through :func:`wire_value`.

    Raises
    ------
    ValueError
        When *rename*, *omit*, *convert* or *after* names a field *obj* does not have (a misspelt field
        would otherwise silently change the wire form).
    """
    names = [f.name for f in dataclasses.fields(obj)]
    rename, convert, after = rename or {}, convert or {}, after or {}
    unknown = (set(rename) | set(omit) | set(convert) | set(after)) - set(names)
    if unknown:
        raise ValueError(f"{type(obj).__name__} has no field {', '.join(sorted(unknown))}")
    out: dict[str, Any] = {}
    for name in names:
        if name not in omit:
            value = getattr(obj, name)
            out[rename.get(name, name)] = convert[name](value) if name in convert else wire_value(value)
        for key, derived in after.get(name, {}).items():
            out[key] = wire_value(derived)
    return out
