"""Metamerism index of a sample against its standard across D65 / A / F11, per geometry.

A thin, reading-level front of :func:`station.model.spectra.metamerism_index` (the one
implementation): the sample is corrected additively in Lab for its mismatch under the reference
illuminant (D65), then the difference under each test illuminant (A, F11) is the index (CIE 15 /
ISO 105-J02 practice). Both readings need spectra on the product's 400–700 nm, 10 nm grid.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from station.model.domain import METAMERISM_TEST_ILLUMINANTS, REFERENCE_ILLUMINANT, aspecular_name
from station.model.spectra import metamerism_index
from station.qc.check import formula_name
from station.qc.errors import QcInputError
from station.qc.readings import Reading

__all__ = ["MetamerismResult", "metamerism"]


@dataclass(frozen=True)
class MetamerismResult:
    """Per geometry: the uncorrected ΔE under D65 and the index under each test illuminant."""

    formula: str
    aspecular_deg: tuple[float, ...]
    reference: tuple[float, ...]
    index: dict[str, tuple[float, ...]]

    def to_dict(self) -> dict[str, Any]:
        return {
            "formula": self.formula,
            "reference_illuminant": REFERENCE_ILLUMINANT,
            "per_geometry": [
                {
                    "geometry": aspecular_name(a),
                    "aspecular_deg": a,
                    "dE_D65": self.reference[i],
                    **{f"MI_{ill}": v[i] for ill, v in self.index.items()},
                }
                for i, a in enumerate(self.aspecular_deg)
            ],
            "max_index": {ill: max(v) for ill, v in self.index.items()},
        }


def metamerism(
    standard: Reading,
    sample: Reading,
    formula: str = "cie2000",
    illuminants: tuple[str, ...] = METAMERISM_TEST_ILLUMINANTS,
) -> MetamerismResult:
    """Metamerism index (D65 → each of *illuminants*, default A and F11) at the geometries both
    readings have, in *formula*. *illuminants* are catalogue names (``station.model.illuminants``)."""
    for r, role in ((standard, "standard"), (sample, "sample")):
        if not r.has_product_spectra():
            raise QcInputError(f"{role}.spectra", "spectra at 400–700 nm in 10 nm steps", r.wavelengths_nm)
    angles = tuple(a for a in standard.aspecular_deg if a in sample.aspecular_deg)
    if not angles:
        raise QcInputError("sample.geometries", f"a geometry of the standard {standard.geometries}", None)
    name = formula_name(formula)
    si = [standard.aspecular_deg.index(a) for a in angles]
    pi = [sample.aspecular_deg.index(a) for a in angles]
    ref = np.asarray(standard.spectra, dtype=float)[si]
    smp = np.asarray(sample.spectra, dtype=float)[pi]
    out = metamerism_index(
        ref, smp, REFERENCE_ILLUMINANT, illuminants, method=name, aspecular_deg=np.asarray(angles)
    )
    return MetamerismResult(
        name,
        angles,
        tuple(float(v) for v in out["reference"]),
        {ill: tuple(float(v) for v in out[ill]) for ill in illuminants},
    )
