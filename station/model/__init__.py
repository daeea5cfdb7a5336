"""Appearance model hierarchy (thesis §3.3, §5.3.3; docs/design.md §3 and §7).

Aspecular measurements ⇄ face/flop/travel/gloss ⇄ clamped quadratic, plus gloss ⇄ specular lobe,
library indices, colour differences, spectra and the design file format. The limits and vocabulary
of the domain (Lab bound, geometry sets and names, gloss range, tolerances) are in
:mod:`station.model.domain`. Every other core package builds on these names, and on the physics they
share: the gloss lobe (:mod:`station.model.lobe`), the reference point-light shading of a design
(:mod:`station.model.shading`) and Lab ⇄ display sRGB (:mod:`station.model.display`).
"""

from typing import TYPE_CHECKING

from station.lazy import lazy_getattr
from station.model.angles import validate_angle_set
from station.model.domain import (
    AB_MAX,
    ANGLES_3,
    ANGLES_3_ALT,
    ANGLES_5,
    ANGLES_6,
    DEFAULT_GLOSS_GU,
    FACE_ANGLE_DEG,
    GLOSS_MAX_GU,
    GLOSS_MIN_GU,
    L_MAX,
    L_MIN,
    LAB_RANGES,
    TRAVEL_MAX_DEG,
    check_gloss,
    check_lab,
    check_travel,
)
from station.model.errors import FitError, ModelError, ModelInputError

if TYPE_CHECKING:
    from station.model.fit import FitResult, fit_fftg
    from station.model.representations import (
        AspecularMeasurements,
        ClampedQuadratic,
        FaceFlopTravelGloss,
    )

#: Names loaded on first use (PEP 562), by module: they import colour-science, which takes a second or
#: more, and the domain's limits and names above must stay cheap for a command line's ``--help``.
_LAZY = {
    "station.model.fit": ("FitResult", "fit_fftg"),
    "station.model.representations": ("AspecularMeasurements", "ClampedQuadratic", "FaceFlopTravelGloss"),
}

__getattr__ = lazy_getattr(__name__, _LAZY)


__all__ = [
    "AB_MAX",
    "ANGLES_3",
    "ANGLES_3_ALT",
    "ANGLES_5",
    "ANGLES_6",
    "DEFAULT_GLOSS_GU",
    "FACE_ANGLE_DEG",
    "GLOSS_MAX_GU",
    "GLOSS_MIN_GU",
    "LAB_RANGES",
    "L_MAX",
    "L_MIN",
    "TRAVEL_MAX_DEG",
    "AspecularMeasurements",
    "ClampedQuadratic",
    "FaceFlopTravelGloss",
    "FitError",
    "FitResult",
    "ModelError",
    "ModelInputError",
    "check_gloss",
    "check_lab",
    "check_travel",
    "fit_fftg",
    "validate_angle_set",
]
