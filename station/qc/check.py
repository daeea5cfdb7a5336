"""Verdict of one sample reading against its standard reading (``station qc check``).

:func:`check_pair` matches the two readings geometry by geometry (aspecular angle) and judges them
with :func:`station.qc.tolerance.judge`:

* with a tolerance set, at the geometries the set names (each must be in both readings, so a missing
  geometry is an error, never a silent pass); geometries the set does not name are not judged;
* without one, at every geometry of the standard (each must be in the sample) with the product's
  default limit :data:`~station.model.domain.QC_DE_LIMIT` at each, in *formula*
  (default :data:`~station.model.domain.QC_FORMULA`).

A *formula* given together with a tolerance set replaces the set's formula (its limits then read in
that formula's units).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence

from station.model.difference import audi2000_unavailable, validate_method
from station.model.domain import QC_FORMULA, aspecular_name
from station.model.errors import ModelInputError
from station.qc.errors import QcInputError
from station.qc.readings import Reading, lab_at
from station.qc.tolerance import FORMULAS, QcVerdict, ToleranceSet, judge

__all__ = ["check_pair", "default_tolerance", "formula_name"]


def formula_name(formula: str) -> str:
    """Canonical formula name (``din6175-2`` → ``din6175``); :class:`QcInputError` for an unknown one."""
    try:
        name = validate_method(formula)
    except ModelInputError as exc:
        raise QcInputError("formula", "din6175-2 | cie2000 | cie94 | cie76", formula) from exc
    if name == "audi2000":
        raise audi2000_unavailable()
    if name not in FORMULAS:
        raise QcInputError("formula", "din6175-2 | cie2000 | cie94 | cie76", formula)
    return name


def default_tolerance(angles: Sequence[float], formula: str | None = None) -> ToleranceSet:
    """The product's default set at *angles* (degrees): ΔE <= QC_DE_LIMIT each, max rule, warn band."""
    return ToleranceSet.uniform(
        tuple(angles), formula=formula_name(formula or QC_FORMULA), name="product default"
    )


def check_pair(
    standard: Reading,
    sample: Reading,
    tolerance: ToleranceSet | None = None,
    formula: str | None = None,
) -> QcVerdict:
    """Pass / warn / fail of *sample* against *standard*, per geometry and overall (module docstring).

    Parameters
    ----------
    standard, sample
        Readings (Lab per aspecular angle, 45° illumination).
    tolerance
        Limits per geometry, formula, aggregation rule and warn band; ``None``: :func:`default_tolerance`
        at the standard's geometries.
    formula
        ``din6175-2`` | ``cie2000`` | ``cie94`` | ``cie76`` (aliases of :mod:`station.model.difference`
        accepted); overrides the tolerance set's formula when both are given.

    Raises
    ------
    QcInputError
        A geometry judged is missing from either reading, or an unknown formula.
    """
    if tolerance is None:
        tol = default_tolerance(standard.aspecular_deg, formula)
    elif formula is not None:
        tol = dataclasses.replace(tolerance, formula=formula_name(formula))
    else:
        tol = tolerance
    angles = [g.aspecular_deg for g in tol.geometries]
    for reading, role in ((standard, "standard"), (sample, "sample")):
        missing = [aspecular_name(a) for a in angles if a not in reading.aspecular_deg]
        if missing:
            raise QcInputError(
                f"{role}.geometries",
                f"every geometry judged ({', '.join(aspecular_name(a) for a in angles)})",
                list(reading.geometries),
                detail=f"missing {', '.join(missing)}",
            )
    return judge(lab_at(standard, angles), lab_at(sample, angles), angles, tol)
