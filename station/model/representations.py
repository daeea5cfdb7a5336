"""The three representations of the appearance model hierarchy (thesis §3.3, docs/design.md §3).

* :class:`FaceFlopTravelGloss` — what a designer edits: face = Lab at 15°, flop = Lab at θ_clamp,
  travel = θ_clamp in degrees, gloss in GU (60° geometry).
* :class:`ClampedQuadratic` — what the renderer and the analyses evaluate: per channel
  X(θ) = X_a θ² + X_b θ + X_c evaluated at min(θ, θ_clamp) (eqs 3.3.1–3.3.2), θ in degrees.
* :class:`AspecularMeasurements` — what instruments report: Lab at aspecular angles plus one gloss.

All three are immutable and validated on construction. Exact conversions join FFTG and the clamped
quadratic (eqs 3.3.4, 3.3.8–3.3.10); measurements are converted by :func:`station.model.fit.fit_fftg`.

Closed form used throughout: with s(θ) = (θ_c − min(θ, θ_c)) / (θ_c − 15°),

    X(θ) = flop + (face − flop) · s(θ)²,

which is eqs 3.3.8–3.3.10 substituted into eq 3.3.1 (all three channels share θ_clamp).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from station.model.angles import validate_angle_set
from station.model.colorimetry import OBSERVER_10
from station.model.domain import (
    DEFAULT_GLOSS_GU,
    FACE_ANGLE_DEG,
    TRAVEL_MAX_DEG,
    Lab,
    check_gloss,
    check_lab,
    check_travel,
)
from station.model.errors import ModelInputError

__all__ = [
    "DEFAULT_GLOSS_GU",
    "FACE_ANGLE_DEG",
    "TRAVEL_MAX_DEG",
    "AspecularMeasurements",
    "ClampedQuadratic",
    "FaceFlopTravelGloss",
    "Lab",
    "check_gloss",
    "check_lab",
    "check_travel",
    "shape_factor",
]


def _as_angles(angles_deg: ArrayLike) -> NDArray[np.float64]:
    theta = np.asarray(angles_deg, dtype=float)
    if not np.all(np.isfinite(theta)):
        raise ModelInputError("angles_deg", "finite aspecular angles in degrees", "non-finite values")
    return theta


def shape_factor(angles_deg: ArrayLike, travel_deg: float | NDArray[np.float64]) -> NDArray[np.float64]:
    """Return s(θ)² = ((θ_c − min(θ, θ_c)) / (θ_c − 15°))², the weight of the face in X(θ).

    Parameters
    ----------
    angles_deg
        Aspecular angles θ in degrees, any shape.
    travel_deg
        θ_clamp in degrees (> 15); an array broadcasts against *angles_deg* (one θ_clamp per row).

    Returns
    -------
    ndarray
        s(θ)², same shape as *angles_deg*; 1 at 15°, 0 at and beyond θ_clamp, > 1 below 15°.

    Notes
    -----
    Eqs 3.3.1, 3.3.2 and 3.3.8–3.3.10 combined: X(θ) = flop + (face − flop) s(θ)².
    The model is a function of the unsigned angle between the view and the specular direction, as
    in the thesis's renderer ("clamped to be between zero and the clamp point", §2.2): a signed
    instrument angle such as −15° (behind gloss) evaluates as 15°.

    Examples
    --------
    With θ_c = 75°, s = (75 − θ)/60: 1 at the face angle, (30/60)² at 45°, 0 from θ_c on; −15° reads as 15°:

    >>> shape_factor([-15, 15, 45, 75, 110], 75.0).tolist()
    [1.0, 1.0, 0.25, 0.0, 0.0]
    """
    theta = np.minimum(np.abs(_as_angles(angles_deg)), travel_deg)
    s = (travel_deg - theta) / (travel_deg - FACE_ANGLE_DEG)
    return s * s


@dataclass(frozen=True)
class FaceFlopTravelGloss:
    """Face/flop/travel/gloss design (thesis §3.3.1).

    Parameters
    ----------
    face
        Lab (D65/10°) at 15° aspecular.
    flop
        Lab at θ_clamp (the travel angle), the colour far from specular.
    travel_deg
        θ_clamp in degrees, 15 < travel <= 180; ``None`` for a solid (face = flop), which has no travel.
    gloss_gu
        Specular gloss in gloss units at the 60° geometry, 0–100.
    name
        Optional label.
    gloss_measured
        Whether *gloss_gu* was measured (a gloss meter) or typed. ``False`` when nobody measured it: the
        gloss then holds the thesis's default for rendering only, and :attr:`gloss_target_gu` is ``None``
        so formulation keeps full gloss (no matting agent for a gloss nobody measured).

    Examples
    --------
    At 45° with θ_c = 75°, s² = 0.25, so X = flop + (face − flop)/4 per channel (eq 3.3.1):

    >>> d = FaceFlopTravelGloss(face=(90, 2, -5), flop=(30, 0.5, -1), travel_deg=75, gloss_gu=85)
    >>> d.lab_at([15, 45, 110]).round(4).tolist()
    [[90.0, 2.0, -5.0], [45.0, 0.875, -2.0], [30.0, 0.5, -1.0]]
    >>> FaceFlopTravelGloss(face=(90, 2, -5), flop=(30, 0.5, -1), travel_deg=12)
    Traceback (most recent call last):
        ...
    station.model.errors.ModelInputError: travel_deg: expected 15 < travel_deg <= 180 (vertex above the face angle), got 12.0
    """

    face: Lab
    flop: Lab
    travel_deg: float | None
    gloss_gu: float = DEFAULT_GLOSS_GU
    name: str = ""
    gloss_measured: bool = True

    def __post_init__(self) -> None:
        object.__setattr__(self, "face", check_lab(self.face, "face"))
        object.__setattr__(self, "flop", check_lab(self.flop, "flop"))
        object.__setattr__(self, "travel_deg", check_travel(self.travel_deg))
        object.__setattr__(self, "gloss_gu", check_gloss(self.gloss_gu))
        if self.travel_deg is None and self.face != self.flop:
            raise ModelInputError(
                "travel_deg",
                f"{FACE_ANGLE_DEG:g} < travel_deg <= {TRAVEL_MAX_DEG:g} when face != flop (None only for a solid)",
                None,
            )

    @property
    def gloss_target_gu(self) -> float | None:
        """The 60° gloss (GU) to formulate to: :attr:`gloss_gu` when measured or typed, else ``None``.

        ``None`` means "not measured": a recipe keeps the clear coat's full gloss instead of adding
        matting agent to reach the thesis's default.
        """
        return self.gloss_gu if self.gloss_measured else None

    @property
    def is_solid(self) -> bool:
        """True when face and flop are identical (no travel)."""
        return self.face == self.flop

    def lab_at(self, angles_deg: ArrayLike) -> NDArray[np.float64]:
        """Evaluate Lab at aspecular angles (degrees) with the clamped quadratic (eqs 3.3.1–3.3.2).

        Returns an array of shape ``angles.shape + (3,)``.
        """
        theta = _as_angles(angles_deg)
        face = np.asarray(self.face)
        flop = np.asarray(self.flop)
        if self.travel_deg is None or self.is_solid:
            return np.broadcast_to(face, (*theta.shape, 3)).copy()
        w = shape_factor(theta, self.travel_deg)[..., None]
        return flop + (face - flop) * w

    def to_quadratic(self) -> ClampedQuadratic:
        """Convert to the parametric form with eqs 3.3.8–3.3.10 (exact)."""
        face = np.asarray(self.face)
        flop = np.asarray(self.flop)
        if self.travel_deg is None:
            coeffs = np.zeros((3, 3))
            coeffs[:, 2] = face
            return ClampedQuadratic(coeffs, None, self.gloss_gu, self.name)
        tc = self.travel_deg
        xa = (face - flop) / (FACE_ANGLE_DEG - tc) ** 2  # eq 3.3.8
        xb = -2.0 * xa * tc  # eq 3.3.9
        xc = flop + xa * tc * tc  # eq 3.3.10
        return ClampedQuadratic(np.stack([xa, xb, xc], axis=1), tc, self.gloss_gu, self.name)

    def replace(self, **changes: Any) -> FaceFlopTravelGloss:
        """Return a copy with *changes* applied (validated again)."""
        return replace(self, **changes)


def _freeze(arr: ArrayLike) -> NDArray[np.float64]:
    out = np.array(arr, dtype=float)
    out.setflags(write=False)
    return out


@dataclass(frozen=True, eq=False)
class ClampedQuadratic:
    """Parametric form (thesis §3.3.2): per channel X(θ) = X_a θ² + X_b θ + X_c at min(θ, θ_clamp).

    Parameters
    ----------
    coefficients
        Shape (3, 3): rows L, a, b; columns (X_a [1/deg²], X_b [1/deg], X_c). Every channel has its
        vertex at θ_clamp (eq 3.3.4) or is constant.
    theta_clamp_deg
        θ_clamp in degrees, or ``None`` for a solid (all channels constant).
    gloss_gu
        Gloss in GU (60°).
    """

    coefficients: NDArray[np.float64]
    theta_clamp_deg: float | None
    gloss_gu: float = DEFAULT_GLOSS_GU
    name: str = ""

    def __post_init__(self) -> None:
        c = np.asarray(self.coefficients, dtype=float)
        if c.shape != (3, 3) or not np.all(np.isfinite(c)):
            raise ModelInputError(
                "coefficients", "a finite 3x3 array (rows L, a, b; columns a, b, c)", c.shape
            )
        object.__setattr__(self, "coefficients", _freeze(c))
        object.__setattr__(self, "theta_clamp_deg", check_travel(self.theta_clamp_deg, "theta_clamp_deg"))
        object.__setattr__(self, "gloss_gu", check_gloss(self.gloss_gu))
        tc = self.theta_clamp_deg
        for i, ch in enumerate("Lab"):
            xa, xb, _ = c[i]
            if tc is None:
                if xa != 0.0 or xb != 0.0:
                    raise ModelInputError(
                        f"coefficients[{ch}]",
                        "constant channels (X_a = X_b = 0) when theta_clamp_deg is None",
                    )
                continue
            # eq 3.3.3: the derivative vanishes at θ_clamp for every channel.
            slope = 2.0 * xa * tc + xb
            scale = max(abs(xb), abs(xa) * tc, 1e-300)
            if abs(slope) > 1e-9 * scale and (xa != 0.0 or xb != 0.0):
                raise ModelInputError(
                    f"coefficients[{ch}]",
                    f"a vertex at theta_clamp_deg = {tc:g} (2 X_a θc + X_b = 0, eq 3.3.3)",
                    float(-xb / (2 * xa)) if xa else "linear",
                )

    @classmethod
    def from_coefficients(
        cls, coefficients: ArrayLike, gloss_gu: float = DEFAULT_GLOSS_GU
    ) -> ClampedQuadratic:
        """Build from coefficients alone, deriving θ_clamp with eq 3.3.4 (from L, or a/b if L is flat)."""
        c = np.asarray(coefficients, dtype=float)
        if c.shape != (3, 3):
            raise ModelInputError("coefficients", "a 3x3 array (rows L, a, b; columns a, b, c)", c.shape)
        tc = None
        for i in range(3):
            if c[i, 0] != 0.0:
                tc = float(-c[i, 1] / (2.0 * c[i, 0]))  # eq 3.3.4
                break
        return cls(c, tc, gloss_gu)

    def lab_at(self, angles_deg: ArrayLike) -> NDArray[np.float64]:
        """Evaluate eq 3.3.2 at aspecular angles in degrees; returns shape ``angles.shape + (3,)``."""
        theta = np.abs(_as_angles(angles_deg))  # unsigned angle from specular, as shape_factor
        if self.theta_clamp_deg is not None:
            theta = np.minimum(theta, self.theta_clamp_deg)
        t = theta[..., None]
        c = self.coefficients
        return (c[:, 0] * t + c[:, 1]) * t + c[:, 2]

    def to_fftg(self) -> FaceFlopTravelGloss:
        """Convert back (thesis §3.3.2): travel = θ_clamp, face = X(15°), flop = X(θ_clamp)."""
        tc = self.theta_clamp_deg
        face = self.lab_at(FACE_ANGLE_DEG)
        if tc is None:
            return FaceFlopTravelGloss(tuple(face), tuple(face), None, self.gloss_gu, self.name)
        flop = self.lab_at(tc)
        return FaceFlopTravelGloss(tuple(face), tuple(flop), tc, self.gloss_gu, self.name)


@dataclass(frozen=True, eq=False)
class AspecularMeasurements:
    """Lab at aspecular angles (illumination at 45°) plus one specular gloss value (thesis §3.3.3).

    Parameters
    ----------
    angles_deg
        Aspecular angles in degrees, strictly increasing, e.g. (15, 45, 110).
    lab
        Shape (n, 3): Lab per angle (D65 / 10° unless *illuminant*/*observer* say otherwise).
    gloss_gu
        Specular gloss at 60° in GU, or None when not measured.
    illuminant, observer
        Colorimetric conditions of *lab*.
    """

    angles_deg: tuple[float, ...]
    lab: NDArray[np.float64]
    gloss_gu: float | None = None
    illuminant: str = "D65"
    observer: str = OBSERVER_10
    warnings: tuple[str, ...] = field(default=())

    def __post_init__(self) -> None:
        angles = validate_angle_set(self.angles_deg)
        object.__setattr__(self, "angles_deg", angles)
        try:
            lab = np.asarray(self.lab, dtype=float)
        except (TypeError, ValueError) as exc:
            raise ModelInputError("lab", "one L*, a*, b* triple per angle", self.lab) from exc
        if lab.ndim != 2 or lab.shape[1] != 3 or lab.shape[0] != len(angles):
            raise ModelInputError("lab", f"{len(angles)} triples L*, a*, b* (one per angle)", lab.shape)
        for i, row in enumerate(lab):
            check_lab(row, f"lab[{i}]")
        object.__setattr__(self, "lab", _freeze(lab))
        object.__setattr__(self, "gloss_gu", check_gloss(self.gloss_gu, allow_none=True))

    @classmethod
    def from_design(cls, design: FaceFlopTravelGloss, angles_deg: Sequence[float]) -> AspecularMeasurements:
        """Evaluate a design at *angles_deg* (thesis §3.3.3: the model → industry standard values)."""
        angles = validate_angle_set(angles_deg)
        return cls(angles, design.lab_at(np.asarray(angles)), design.gloss_gu)
