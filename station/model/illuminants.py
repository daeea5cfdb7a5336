"""The booth's illuminant names: one validation rule for every front (CLI, service, viewer).

Names are checked against colour-science's illuminant table through the product's aliases
(:mod:`station.model.spectra`); the reference illuminant of the metamerism index is D65.
"""

from __future__ import annotations

from typing import Final

import colour

from station.model.errors import ModelInputError

__all__ = ["BOOTH_ILLUMINANTS", "REFERENCE_ILLUMINANT", "illuminant_name"]

#: The booth's illuminants, in the order a booth's switch offers them.
BOOTH_ILLUMINANTS: Final = ("D65", "D50", "A", "F2", "F11")
#: The reference illuminant of the metamerism index and of the product's Lab.
REFERENCE_ILLUMINANT: Final = "D65"


def illuminant_name(name: str) -> str:
    """Catalogue name of *name* (case-insensitive); :class:`ModelInputError` for an unknown one."""
    text = str(name).strip()
    for known in BOOTH_ILLUMINANTS:
        if text.upper() == known.upper():
            return known
    if text in colour.SDS_ILLUMINANTS:
        return text
    raise ModelInputError("illuminant", f"one of {', '.join(BOOTH_ILLUMINANTS)}", name)
