"""Appearance model hierarchy (thesis §3.3, §5.3.3; DESIGN.md §3 and §7).

Aspecular measurements ⇄ face/flop/travel/gloss ⇄ clamped quadratic, plus gloss ⇄ specular lobe,
library indices, colour differences, spectra and the design file format. Every other core package
builds on these names, and on the physics they share: the gloss lobe (:mod:`station.model.lobe`), the
reference point-light shading of a design (:mod:`station.model.shading`) and Lab ⇄ display sRGB
(:mod:`station.model.display`).
"""

from station.model.angles import ANGLES_3, ANGLES_3_ALT, ANGLES_5, ANGLES_6, validate_angle_set
from station.model.errors import FitError, ModelError, ModelInputError
from station.model.fit import FitResult, fit_fftg
from station.model.representations import (
    DEFAULT_GLOSS_GU,
    FACE_ANGLE_DEG,
    AspecularMeasurements,
    ClampedQuadratic,
    FaceFlopTravelGloss,
)

__all__ = [
    "ANGLES_3",
    "ANGLES_3_ALT",
    "ANGLES_5",
    "ANGLES_6",
    "DEFAULT_GLOSS_GU",
    "FACE_ANGLE_DEG",
    "AspecularMeasurements",
    "ClampedQuadratic",
    "FaceFlopTravelGloss",
    "FitError",
    "FitResult",
    "ModelError",
    "ModelInputError",
    "fit_fftg",
    "validate_angle_set",
]
