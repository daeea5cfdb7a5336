"""A second, real library: the Munsell renotation colours (real set, 2734 chips) as solids.

Source: colour-science's ``MUNSELL_COLOURS_REAL`` (Newhall, Nickerson & Judd 1943 renotation, xyY under
Illuminant C, CIE 1931 2° observer, Y in 0–100 relative to the ideal white). Conversion to our Lab
(D65 / CIE 1964 10°): xyY → XYZ, CAT02 von Kries adaptation from C to the D65 white, Lab against the
D65 10° white point. The observer cannot be converted from tristimulus values alone, so the Lab is
approximate (a 2° → 10° observer difference of typically 1–2 ΔE*ab); the library says so in its name.
Every chip is a solid (same Lab at every angle, no recipe), gloss unknown (90 GU assumed: the chips
are glossy).
"""

from __future__ import annotations

import functools

import numpy as np

from station.formulate.library import STANDARD_ANGLES, Library
from station.model.colorimetry import WHITEPOINT, xyz_to_lab

MUNSELL_NAME = "Munsell renotation (real, Illuminant C / 2° adapted to D65 / 10°: approximate), solids"


@functools.lru_cache(maxsize=1)
def munsell_library() -> Library:
    """Return the Munsell renotation library (2734 solids, Lab at 15/45/110 identical)."""
    import colour  # colour-science (about a second) is loaded when the library is first built

    data = colour.notation.MUNSELL_COLOURS_REAL
    codes = np.array([f"MUNSELL {h} {v:g}/{c:g}" for (h, v, c), _ in data])
    xyy = np.array([v for _, v in data], dtype=np.float64)
    xyz = colour.xyY_to_XYZ(xyy * np.array([1.0, 1.0, 0.01]))
    c_white = colour.xy_to_XYZ(colour.CCS_ILLUMINANTS["CIE 1931 2 Degree Standard Observer"]["C"])
    d65_white = colour.xy_to_XYZ(WHITEPOINT)
    m = colour.adaptation.matrix_chromatic_adaptation_VonKries(c_white, d65_white, "CAT02")
    lab = xyz_to_lab(xyz @ np.asarray(m).T)
    n = len(codes)
    return Library(
        name=MUNSELL_NAME,
        codes=codes,
        types=np.full(n, "solid"),
        gloss_gu=np.full(n, 90.0),
        angles_deg=STANDARD_ANGLES,
        lab=np.repeat(lab[:, None, :], 3, axis=1),
        synthetic=False,
        source="colour-science MUNSELL_COLOURS_REAL",
    )
