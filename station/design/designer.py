"""Designer operations of the goniochromatic colour design interface (thesis §3.4.1–§3.4.5).

Every operation is a pure function: it takes an immutable design (:class:`FaceFlopTravelGloss`) or an
immutable set of data points (:class:`DataPoints`) and returns a new one. A request the model cannot
represent raises :class:`~station.design.errors.DesignInputError` (or the model's own
:class:`~station.model.ModelInputError`, which is also an ``InputError``) naming the field and the
accepted range; nothing is clamped silently.

Units: L*, a*, b* (D65/10°), angles in degrees, gloss in GU (60° geometry).
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from station.design.errors import DesignInputError
from station.model import (
    ANGLES_5,
    FACE_ANGLE_DEG,
    GLOSS_MAX_GU,
    GLOSS_MIN_GU,
    TRAVEL_MAX_DEG,
    AspecularMeasurements,
    FaceFlopTravelGloss,
    FitResult,
    ModelError,
    ModelInputError,
    fit_fftg,
)
from station.model.domain import check_lab_channel

Channel = Literal["L", "a", "b"]
CHANNELS: tuple[Channel, ...] = ("L", "a", "b")


def _finite(value: float, name: str) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError) as exc:
        raise DesignInputError(name, "a finite number", value) from exc
    if not math.isfinite(v):
        raise DesignInputError(name, "a finite number", value)
    return v


def check_channel(channel: str, value: float, name: str) -> float:
    """Check one Lab coordinate against the domain's effect-paint bound (``station.model.domain``).

    Raises
    ------
    DesignInputError
        With the field and the accepted range of :func:`station.model.domain.check_lab_channel`
        (e.g. ``face.L: expected 0 <= L* <= 200``): the same message every front shows.
    """
    try:
        return check_lab_channel(channel, _finite(value, name), name)
    except ModelInputError as exc:
        raise DesignInputError(exc.field, exc.accepted, exc.got) from exc


# ------------------------------------------------------------------------------- data-point editor


@dataclass(frozen=True)
class DataPoints:
    """The data points of the L, a and b plots (thesis §3.4.1): Lab at aspecular angles.

    ``angles_deg`` is strictly increasing; ``lab`` is a tuple of ``(L, a, b)`` tuples, one per angle.
    """

    angles_deg: tuple[float, ...]
    lab: tuple[tuple[float, float, float], ...]
    gloss_gu: float

    def as_array(self) -> NDArray[np.float64]:
        """Lab as an ``(n, 3)`` array."""
        return np.array(self.lab, dtype=float)

    def fit(self) -> FitResult:
        """Refit the clamped quadratic through the points (``station.model.fit_fftg``, eqs 3.3.1–3.3.10)."""
        return fit_fftg(AspecularMeasurements(self.angles_deg, self.as_array(), self.gloss_gu))


def data_points(design: FaceFlopTravelGloss, angles_deg: tuple[float, ...] = ANGLES_5) -> DataPoints:
    """Sample *design* at *angles_deg* (default the 5-angle set 15/25/45/75/110) as editable points."""
    angles = tuple(float(a) for a in angles_deg)
    if len(angles) < 3 or any(b <= a for a, b in itertools.pairwise(angles)):
        raise DesignInputError("angles_deg", "at least 3 strictly increasing angles", angles_deg)
    lab = design.lab_at(np.array(angles))
    return DataPoints(angles, tuple((float(L), float(a), float(b)) for L, a, b in lab), design.gloss_gu)


@dataclass(frozen=True)
class PointEdit:
    """Result of a data-point edit: the new points and the live refit (design, residual ΔE per angle)."""

    points: DataPoints
    fit: FitResult

    @property
    def design(self) -> FaceFlopTravelGloss:
        """The refitted design."""
        return self.fit.design


def move_point(points: DataPoints, channel: Channel, angle_deg: float, value: float) -> PointEdit:
    """Move the data point of *channel* (``"L"``, ``"a"`` or ``"b"``) at *angle_deg* to *value* and refit.

    Thesis §3.4.1: "As a point is moved, the clamped quadratic polynomial that interpolates the data
    points is updated in real-time." The refit is ``station.model.fit_fftg`` (closed form for 3
    angles, least squares otherwise); its residual ΔE*ab per angle tells how far the curve now
    misses the points.

    Raises
    ------
    DesignInputError
        Unknown channel, an angle that is not one of the points, or a value out of range
        (the domain's Lab bound, :data:`station.model.domain.LAB_RANGES`).
    station.model.FitError
        The model cannot be fitted through the moved points (e.g. a vertex below 15°).
    """
    if channel not in CHANNELS:
        raise DesignInputError("channel", "L | a | b", channel)
    angle = _finite(angle_deg, "angle_deg")
    matches = [i for i, a in enumerate(points.angles_deg) if abs(a - angle) < 1e-9]
    if not matches:
        raise DesignInputError("angle_deg", f"one of {points.angles_deg}", angle_deg)
    k = CHANNELS.index(channel)
    v = check_channel(channel, value, "value")
    lab = [list(row) for row in points.lab]
    lab[matches[0]][k] = v
    new = DataPoints(points.angles_deg, tuple((L, a, b) for L, a, b in lab), points.gloss_gu)
    return PointEdit(new, new.fit())


# ------------------------------------------------------------------------ hue/saturation/brightness


def _rotate_scale(lab: NDArray, hue_deg: float, saturation: float, brightness: float) -> NDArray:
    h = math.radians(hue_deg)
    c, s = math.cos(h), math.sin(h)
    out = np.array(lab, dtype=float)
    a, b = out[..., 1].copy(), out[..., 2].copy()
    out[..., 1] = saturation * (c * a - s * b)
    out[..., 2] = saturation * (s * a + c * b)
    out[..., 0] = out[..., 0] + brightness
    return out


def _check_hsb(hue_deg: float, saturation: float, brightness: float) -> tuple[float, float, float]:
    h = _finite(hue_deg, "hue_deg")
    s = _finite(saturation, "saturation")
    if s < 0:
        raise DesignInputError("saturation", "a scale factor >= 0", s)
    return h, s, _finite(brightness, "brightness")


def hsb_edit_points(
    points: DataPoints, hue_deg: float = 0.0, saturation: float = 1.0, brightness: float = 0.0
) -> PointEdit:
    """Group edit of every data point (thesis §3.4.2) and refit.

    The a–b points are rotated by *hue_deg* about the origin and scaled by *saturation*; *brightness*
    is added to every L*. Rotation and uniform scale are a similarity, so the relative spacing of the
    points (their shape in the a–b plane) is kept; distances scale by *saturation*.
    """
    h, s, b = _check_hsb(hue_deg, saturation, brightness)
    lab = _rotate_scale(points.as_array(), h, s, b)
    for i, row in enumerate(lab):
        _lab(row, f"lab[{i}]")
    new = DataPoints(
        points.angles_deg, tuple((float(L), float(a), float(b)) for L, a, b in lab), points.gloss_gu
    )
    return PointEdit(new, new.fit())


def hsb_edit(
    design: FaceFlopTravelGloss, hue_deg: float = 0.0, saturation: float = 1.0, brightness: float = 0.0
) -> FaceFlopTravelGloss:
    """Hue/saturation/brightness group edit of a design (thesis §3.4.2), exact.

    Applies the rotation/scale of :func:`hsb_edit_points` to face and flop. The clamped quadratic is
    an affine blend of face and flop at every angle (X(θ) = flop + (face − flop) s(θ)²), and the
    edit is affine, so the result equals editing *every* point on the curve and refitting.
    """
    h, s, b = _check_hsb(hue_deg, saturation, brightness)
    face, flop = _rotate_scale(np.array([design.face, design.flop]), h, s, b)
    return design.replace(face=_lab(face, "face"), flop=_lab(flop, "flop"), travel_deg=design.travel_deg)


# --------------------------------------------------------------------- face/flop/travel picker


def _lab(value: ArrayLike, name: str) -> tuple[float, float, float]:
    arr = np.asarray(value, dtype=float).reshape(-1)
    if arr.size != 3 or not np.all(np.isfinite(arr)):
        raise DesignInputError(name, "three finite numbers L*, a*, b*", value)
    L, a, b = (check_channel(ch, float(v), f"{name}.{ch}") for ch, v in zip("Lab", arr, strict=True))
    return (L, a, b)


def _solid_safe(
    design: FaceFlopTravelGloss, face: tuple, flop: tuple, travel: float | None, default_travel: float
) -> FaceFlopTravelGloss:
    """Build the edited design; a solid that stops being solid gets *default_travel*; equal → solid."""
    if face == flop:
        travel = None
    elif travel is None:
        travel = default_travel
    try:
        return design.replace(face=face, flop=flop, travel_deg=travel)
    except ModelError as exc:
        raise DesignInputError("design", "a design the model can represent", None, str(exc)) from exc


DEFAULT_TRAVEL_DEG = 75.0


def move_face(
    design: FaceFlopTravelGloss,
    a: float,
    b: float,
    L: float | None = None,
    default_travel: float = DEFAULT_TRAVEL_DEG,
) -> FaceFlopTravelGloss:
    """Move the arrowhead (face, Lab at 15°) to (*a*, *b*) and optionally to *L* (thesis §3.4.3).

    A solid that gains a distinct face gets travel *default_travel* (degrees).
    """
    face = _lab((design.face[0] if L is None else L, a, b), "face")
    return _solid_safe(design, face, design.flop, design.travel_deg, default_travel)


def move_flop(
    design: FaceFlopTravelGloss,
    a: float,
    b: float,
    L: float | None = None,
    default_travel: float = DEFAULT_TRAVEL_DEG,
) -> FaceFlopTravelGloss:
    """Move the arrow's base (flop, Lab at θ_clamp) to (*a*, *b*) and optionally to *L* (thesis §3.4.3)."""
    flop = _lab((design.flop[0] if L is None else L, a, b), "flop")
    return _solid_safe(design, design.face, flop, design.travel_deg, default_travel)


def move_arrow(design: FaceFlopTravelGloss, da: float, db: float) -> FaceFlopTravelGloss:
    """Drag the whole face→flop arrow by (*da*, *db*) in the a–b plane (thesis §3.4.3); L* unchanged."""
    da, db = _finite(da, "da"), _finite(db, "db")
    face = _lab((design.face[0], design.face[1] + da, design.face[2] + db), "face")
    flop = _lab((design.flop[0], design.flop[1] + da, design.flop[2] + db), "flop")
    return _solid_safe(design, face, flop, design.travel_deg, DEFAULT_TRAVEL_DEG)


def set_travel(design: FaceFlopTravelGloss, travel_deg: float) -> FaceFlopTravelGloss:
    """Drag the flop/travel control horizontally: set θ_clamp (degrees, FACE_ANGLE_DEG < travel <=
    TRAVEL_MAX_DEG, i.e. 15 < travel <= 180).

    A solid has no travel; setting one on a solid is refused (move face or flop first).
    """
    t = _finite(travel_deg, "travel_deg")
    if design.is_solid:
        raise DesignInputError("travel_deg", "no travel on a solid design (face = flop)", t)
    if not FACE_ANGLE_DEG < t <= TRAVEL_MAX_DEG:
        raise DesignInputError("travel_deg", f"{FACE_ANGLE_DEG:g} < travel_deg <= {TRAVEL_MAX_DEG:g}", t)
    return design.replace(travel_deg=t)


# ------------------------------------------------------------------------------------------- gloss


def set_gloss(design: FaceFlopTravelGloss, gloss_gu: float) -> FaceFlopTravelGloss:
    """Gloss slider (thesis §3.4.5): 0–100 GU at 60°; the renderer maps it to a Phong lobe with
    ``station.model.gloss.lobe_from_gloss`` (Westlund & Meyer)."""
    g = _finite(gloss_gu, "gloss_gu")
    if not GLOSS_MIN_GU <= g <= GLOSS_MAX_GU:
        raise DesignInputError("gloss_gu", f"{GLOSS_MIN_GU:g} <= gloss_gu <= {GLOSS_MAX_GU:g}", g)
    return design.replace(gloss_gu=g)
