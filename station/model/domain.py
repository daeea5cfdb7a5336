"""Limits and vocabulary of the domain: the one place where they are written.

Every package (model, design, render, analysis, formulate, the service, the CLI and the viewer) imports
its Lab bounds, face angle, travel and gloss ranges, standard geometry sets, geometry names and
tolerance defaults from here, and every bad value gets the same :class:`ModelInputError` naming the
field and the accepted range. ``tests/test_architecture.py`` fails when a numeric Lab bound or a
standard geometry list is written anywhere else.

Lab bound for effect paints
---------------------------
``0 <= L* <= 200`` and ``-150 <= a*, b* <= 150`` (D65/10°). L* above 100 is normal for effect paints
near specular: aluminium (silver) paints read L*15 of 110–140 on a multi-angle instrument (Perales et
al., "Evaluation of a multi-angle colour metric for effect coatings", 2011), and the near-specular
−15° ASTM E2194 geometry reads higher still, so the upper bound leaves headroom to 200. |a*|, |b*| up
to 150 covers every real surface colour (the most saturated pigments stay below 130).

Geometries
----------
Angles are aspecular (degrees from the specular direction in the plane of illumination, positive
towards the illumination; thesis §3.3.3, ASTM E2194) under 45° illumination. Instruments and CxF/X-Rite
files name a geometry ``"<illumination>as<aspecular>"``: ``45as15``, ``45as-15``, ``15as-15``.
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping
from types import MappingProxyType
from typing import Literal, get_args

import numpy as np
from numpy.typing import ArrayLike

from station.model.errors import ModelInputError

Lab = tuple[float, float, float]

# ------------------------------------------------------------------------------------------ Lab

#: Lightness bound of a stated colour, L* (D65/10°). L* > 100 is real for effect paints (module doc).
L_MIN, L_MAX = 0.0, 200.0
#: Bound on |a*| and |b*| of a stated colour.
AB_MAX = 150.0
#: The Lab bound per channel, ``{"L": (lo, hi), "a": …, "b": …}`` (read-only).
LAB_RANGES: Mapping[str, tuple[float, float]] = MappingProxyType(
    {"L": (L_MIN, L_MAX), "a": (-AB_MAX, AB_MAX), "b": (-AB_MAX, AB_MAX)}
)
#: L* of the perfect diffuse white. Surface colours seen off specular stay at or below it (Pointer's
#: gamut is defined up to it, and it is the usual top of an L* plot); effect paints exceed it near
#: specular, which is why the bound is :data:`L_MAX`.
DIFFUSE_WHITE_L = 100.0
#: Default axes of Lab plots (display only; a plot extends them to show every value in the bound).
LAB_PLOT_RANGES: Mapping[str, tuple[float, float]] = MappingProxyType(
    {"L": (L_MIN, DIFFUSE_WHITE_L), "a": (-80.0, 80.0), "b": (-80.0, 80.0)}
)


def plot_range(channel: str, values: ArrayLike = ()) -> tuple[float, float]:
    """Axis of a Lab plot: :data:`LAB_PLOT_RANGES` widened in steps of 20 to show every finite value
    of *values*, never beyond the bound :data:`LAB_RANGES` (display only, not a validation)."""
    lo, hi = LAB_PLOT_RANGES[channel]
    v = np.asarray(values, dtype=float).reshape(-1)
    v = v[np.isfinite(v)]
    if v.size:
        lo = min(lo, 20.0 * math.floor(float(v.min()) / 20.0))
        hi = max(hi, 20.0 * math.ceil(float(v.max()) / 20.0))
    b_lo, b_hi = LAB_RANGES[channel]
    return max(lo, b_lo), min(hi, b_hi)


#: Largest reflectance (radiance) factor a spectrum may state: the one whose L* is :data:`L_MAX`
#: (Y = ((L* + 16) / 116)³ ≈ 6.5). Flake reflection near specular exceeds a white diffuser (R > 1):
#: bright silvers read L*15 of 110–140, R ≈ 1.4–2.4.
REFLECTANCE_MAX = ((L_MAX + 16.0) / 116.0) ** 3

#: Lower and upper Lab bounds as (L*, a*, b*) triples, for vectorised checks.
LAB_LO: Lab = (L_MIN, -AB_MAX, -AB_MAX)
LAB_HI: Lab = (L_MAX, AB_MAX, AB_MAX)
LAB_CHANNELS: tuple[str, str, str] = ("L", "a", "b")


def lab_accepted(channel: str) -> str:
    """Return the accepted range of one Lab channel as text, e.g. ``"0 <= L* <= 200"``.

    Examples
    --------
    >>> lab_accepted("L"), lab_accepted("b")
    ('0 <= L* <= 200', '-150 <= b* <= 150')
    """
    lo, hi = LAB_RANGES[channel]
    return f"{lo:g} <= {channel}* <= {hi:g}"


def check_lab_channel(channel: str, value: float, field: str) -> float:
    """Validate one Lab coordinate against :data:`LAB_RANGES`.

    Parameters
    ----------
    channel
        ``"L"``, ``"a"`` or ``"b"``.
    value
        The coordinate (CIELAB units).
    field
        Name used in the error, e.g. ``"face.L"``.

    Raises
    ------
    ModelInputError
        Naming *field* and the range (``"0 <= L* <= 200"``) when *value* is not a finite number in it.
    """
    if channel not in LAB_RANGES:
        raise ModelInputError("channel", "L | a | b", channel)
    try:
        v = float(value)
    except (TypeError, ValueError) as exc:
        raise ModelInputError(field, f"a number, {lab_accepted(channel)}", value) from exc
    lo, hi = LAB_RANGES[channel]
    if not math.isfinite(v):
        raise ModelInputError(field, "a finite number", v)
    if not lo <= v <= hi:
        raise ModelInputError(field, lab_accepted(channel), v)
    return v


def check_lab(value: ArrayLike, field: str) -> Lab:
    """Validate one Lab triple against the effect-paint bound; return it as a tuple of floats.

    The accepted range is ``0 <= L* <= 200``, ``-150 <= a*, b* <= 150`` (module docstring for the
    source). The error names the channel, e.g. ``face.L: expected 0 <= L* <= 200, got 250.0``.

    Raises
    ------
    ModelInputError
        Not three numbers, a non-finite number, or a coordinate outside the bound.

    Examples
    --------
    An effect paint's face above L* 100 is valid; a coordinate outside the bound names its channel:

    >>> check_lab([125, -0.6, -1.8], "face")
    (125.0, -0.6, -1.8)
    >>> check_lab((250, 0, 0), "face")
    Traceback (most recent call last):
        ...
    station.model.errors.ModelInputError: face.L: expected 0 <= L* <= 200, got 250.0
    """
    try:
        arr = np.asarray(value, dtype=float).reshape(-1)
    except (TypeError, ValueError) as exc:
        raise ModelInputError(field, "three numbers L*, a*, b*", value) from exc
    if arr.size != 3:
        raise ModelInputError(field, "three numbers L*, a*, b*", value)
    out = tuple(
        check_lab_channel(ch, float(v), f"{field}.{ch}") for ch, v in zip(LAB_CHANNELS, arr, strict=True)
    )
    return (out[0], out[1], out[2])


def lab_within(value: ArrayLike) -> bool:
    """True when every Lab triple in *value* (shape ``(..., 3)``) is finite and inside the bound.

    Examples
    --------
    >>> lab_within([[50, 0, 0], [200, -150, 150]]), lab_within([[50, 0, 0], [201, 0, 0]])
    (True, False)
    """
    arr = np.asarray(value, dtype=float)
    return bool(((arr >= np.asarray(LAB_LO)) & (arr <= np.asarray(LAB_HI))).all())


# ------------------------------------------------------------------------------ angles, travel

#: Face angle of the model in degrees (thesis §3.3.1; docs/design.md erratum 3).
FACE_ANGLE_DEG = 15.0
#: Accepted travel (θ_clamp) range: FACE_ANGLE_DEG < travel <= TRAVEL_MAX_DEG degrees.
TRAVEL_MAX_DEG = 180.0
#: Illumination angle of the standard multi-angle geometries, degrees from the normal.
ILLUMINATION_DEG = 45.0
#: Accepted aspecular angle range in degrees. At 45° illumination the in-plane aspecular angle runs
#: from −45° to 135°; −90 … 180 lets out-of-plane geometries fit too.
ANGLE_MIN_DEG = -90.0
ANGLE_MAX_DEG = 180.0


def check_travel(value: float | None, field: str = "travel_deg") -> float | None:
    """Validate θ_clamp in degrees: FACE_ANGLE_DEG < travel <= TRAVEL_MAX_DEG, or None (a solid).

    Examples
    --------
    >>> check_travel(75), check_travel(None)
    (75.0, None)
    >>> check_travel(12.0)
    Traceback (most recent call last):
        ...
    station.model.errors.ModelInputError: travel_deg: expected 15 < travel_deg <= 180 (vertex above the face angle), got 12.0
    """
    if value is None:
        return None
    try:
        t = float(value)
    except (TypeError, ValueError) as exc:
        raise ModelInputError(field, "a number of degrees", value) from exc
    if not math.isfinite(t) or not (FACE_ANGLE_DEG < t <= TRAVEL_MAX_DEG):
        raise ModelInputError(
            field,
            f"{FACE_ANGLE_DEG:g} < travel_deg <= {TRAVEL_MAX_DEG:g} (vertex above the face angle)",
            t,
        )
    return t


# ---------------------------------------------------------------------------------------- gloss

#: Accepted gloss range of a design, gloss units at the 60° geometry.
GLOSS_MIN_GU, GLOSS_MAX_GU = 0.0, 100.0
#: Gloss used when a design does not state one (the thesis's sketch-fit default, §3.7).
DEFAULT_GLOSS_GU = 50.0


def check_gloss(value: float | None, field: str = "gloss_gu", allow_none: bool = False) -> float | None:
    """Validate a gloss value in GU (60°): finite, GLOSS_MIN_GU <= g <= GLOSS_MAX_GU.

    Examples
    --------
    >>> check_gloss(85)
    85.0
    >>> check_gloss(120.0)
    Traceback (most recent call last):
        ...
    station.model.errors.ModelInputError: gloss_gu: expected 0 <= gloss_gu <= 100, got 120.0
    """
    if value is None:
        if allow_none:
            return None
        raise ModelInputError(field, f"{GLOSS_MIN_GU:g} <= gloss_gu <= {GLOSS_MAX_GU:g}", value)
    try:
        g = float(value)
    except (TypeError, ValueError) as exc:
        raise ModelInputError(field, "a number of gloss units", value) from exc
    if not math.isfinite(g) or not (GLOSS_MIN_GU <= g <= GLOSS_MAX_GU):
        raise ModelInputError(field, f"{GLOSS_MIN_GU:g} <= gloss_gu <= {GLOSS_MAX_GU:g}", g)
    return g


def check_ranged(field: str, value: object, lo: float, hi: float, name: str | None = None) -> float:
    """A real number (not a bool) with lo <= value <= hi, as float; :class:`ModelInputError` naming *field*
    with the range ``lo <= name <= hi`` otherwise (*name* defaults to the last part of *field*).

    Examples
    --------
    >>> check_ranged("coat.index", 1.5, 1.3, 2.0)
    1.5
    >>> check_ranged("coat.index", True, 1.3, 2.0)
    Traceback (most recent call last):
        ...
    station.model.errors.ModelInputError: coat.index: expected 1.3 <= index <= 2.0, got True
    """
    label = name or field.rsplit(".", 1)[-1]
    if (
        isinstance(value, bool)
        or not isinstance(value, (int, float))
        or not math.isfinite(value)
        or not lo <= value <= hi
    ):
        raise ModelInputError(field, f"{lo} <= {label} <= {hi}", value)
    return float(value)


# ----------------------------------------------------------------------------- geometry sets

#: The common 3-angle set (ASTM E2194), aspecular degrees.
ANGLES_3: tuple[float, ...] = (15.0, 45.0, 110.0)
#: The alternative 3-angle set, degrees.
ANGLES_3_ALT: tuple[float, ...] = (25.0, 45.0, 75.0)
#: The 5-angle set of 5-angle instruments, degrees.
ANGLES_5: tuple[float, ...] = (15.0, 25.0, 45.0, 75.0, 110.0)
#: The ASTM E2194 6-angle set with the behind-gloss −15° angle, degrees.
ANGLES_6: tuple[float, ...] = (-15.0, 15.0, 25.0, 45.0, 75.0, 110.0)
#: Every standard set by name.
STANDARD_ANGLE_SETS: Mapping[str, tuple[float, ...]] = MappingProxyType(
    {"3": ANGLES_3, "3-alt": ANGLES_3_ALT, "5": ANGLES_5, "6": ANGLES_6}
)

_GEOMETRY = re.compile(r"^(-?\d+(?:\.\d+)?)as(-?\d+(?:\.\d+)?)$")


def format_angle(angle_deg: float) -> str:
    """Angle as geometry names write it: ``15.0`` → ``"15"``, ``-15`` → ``"-15"``, ``12.5`` → ``"12.5"``.

    Examples
    --------
    >>> format_angle(15.0), format_angle(-15), format_angle(12.5)
    ('15', '-15', '12.5')
    """
    a = float(angle_deg)
    return str(int(a)) if a.is_integer() else repr(a)


def geometry_name(illumination_deg: float, aspecular_deg: float) -> str:
    """Return the CxF/X-Rite name of a geometry, e.g. ``geometry_name(45, -15) == "45as-15"``."""
    return f"{format_angle(illumination_deg)}as{format_angle(aspecular_deg)}"


def aspecular_name(aspecular_deg: float) -> str:
    """Name of an aspecular angle under the standard 45° illumination, e.g. ``"45as110"``."""
    return geometry_name(ILLUMINATION_DEG, aspecular_deg)


def parse_geometry(name: str, field: str = "geometry") -> tuple[float, float]:
    """Return ``(illumination_deg, aspecular_deg)`` of a name like ``"45as15"`` or ``"15as-15"``.

    Raises
    ------
    ModelInputError
        The name is not ``<illumination>as<aspecular>`` with numbers in degrees.

    Examples
    --------
    >>> parse_geometry("45as110"), parse_geometry("15as-15")
    ((45.0, 110.0), (15.0, -15.0))
    >>> geometry_name(*parse_geometry("45as-15")) == aspecular_name(-15) == "45as-15"
    True
    """
    m = _GEOMETRY.match(str(name).strip())
    if m is None:
        raise ModelInputError(field, 'a name like "45as15" (illumination "as" aspecular)', name)
    return float(m.group(1)), float(m.group(2))


# ------------------------------------------------------------------------------ tolerances

#: The light booth's illuminants, in the order a booth's switch offers them (TL84 is F11's lamp; a user
#: SPD file adds its own), the reference of the product's Lab and of the metamerism index, and the
#: illuminants a booth comparison and the QC metamerism index use when none are chosen.
BOOTH_ILLUMINANTS: tuple[str, ...] = ("D65", "D50", "A", "F2", "F11", "TL84", "LED-B3", "LED-B4")
REFERENCE_ILLUMINANT = "D65"
DEFAULT_BOOTH_ILLUMINANTS: tuple[str, ...] = ("D65", "A", "F11")
METAMERISM_TEST_ILLUMINANTS: tuple[str, ...] = ("A", "F11")
#: What the light booth shows standard and sample on: two flat panels side by side, a bumper/fender seam,
#: a car.
BOOTH_SHAPES: tuple[str, ...] = ("panels", "seam", "car")
#: Colour-difference formulas by the names every front accepts (``station.model.difference`` holds
#: their implementations under exactly these keys); ``audi2000`` is named but licensed separately.
DELTA_E_METHOD_NAMES: tuple[str, ...] = ("cie76", "cie94", "cie2000", "din6175", "audi2000")
#: The formulas the product computes itself (every name above but the separately licensed one), as a type
#: for the fronts' schemas and as the tuple the checks read (one list: the tuple is derived from the type).
DeltaEComputed = Literal["cie76", "cie94", "cie2000", "din6175"]
DELTA_E_COMPUTED: tuple[str, ...] = get_args(DeltaEComputed)
#: The formulas an environment-lit analysis takes: DIN 6175-2 weighs by the aspecular angle of a point
#: light, which an environment does not have (``station.analysis.seam_model``).
DeltaEEnvironment = Literal["cie76", "cie94", "cie2000"]
DELTA_E_ENVIRONMENT: tuple[str, ...] = get_args(DeltaEEnvironment)
#: The formulas ColorSnap ranks a library by (``station.formulate.de_kernels.KERNELS``).
SnapMetric = Literal["cie76", "cie2000", "din6175"]
SNAP_METRICS: tuple[str, ...] = get_args(SnapMetric)
#: Paint types of the library, of its filters and of the toner lines.
PaintType = Literal["solid", "metallic", "pearl"]
PAINT_TYPES: tuple[str, ...] = get_args(PaintType)
#: Rules that turn per-geometry colour differences into one tolerance verdict (QC).
TOLERANCE_AGGREGATIONS: tuple[str, ...] = ("max", "mean")

#: One just-noticeable difference in ΔE*ab (CIE76), the thesis's ε (§4.3).
JND_CIE76 = 2.3
#: The stated resolution of the goniogeometric index β_min (degrees, eq 4.3.1).
INDEX_RESOLUTION_DEG = 1e-6
#: The largest misalignment β_max an index search may be asked for (degrees): from the index's resolution
#: (a search below it can answer nothing, and its grid spacing underflows) to 89°.
BETA_MAX_RANGE_DEG: tuple[float, float] = (INDEX_RESOLUTION_DEG, 89.0)
#: The index's bracketing grid step (degrees): from 0.001° (at most 89 001 grid points a row) to 1°.
GRID_STEP_RANGE_DEG: tuple[float, float] = (1e-3, 1.0)
#: Default formulation tolerance: mean CIEDE2000 over the angles for "formulable" (formulation-qc).
FORMULATION_TOLERANCE_DE00 = 1.0
#: Toner lines a recipe is drawn from (station.formulate.lines), one per paint type: solids get no effect
#: pigment.
TONER_LINES: tuple[str, ...] = PAINT_TYPES
#: Default and accepted range of the number of colorants in a recipe, the binder not counted.
DEFAULT_MAX_COLORANTS = 5
MAX_COLORANTS_RANGE: tuple[int, int] = (1, 10)
#: Default scale resolution (g): recipe amounts are rounded to it (the smallest weighable amount).
DEFAULT_SCALE_RESOLUTION_G = 0.1
SCALE_RESOLUTION_RANGE_G: tuple[float, float] = (0.001, 10.0)
#: Default and accepted range of the number of alternative recipes a formulation returns.
DEFAULT_RECIPE_COUNT = 3
RECIPE_COUNT_RANGE: tuple[int, int] = (1, 10)
#: Default threshold of a systematic sketch misfit: 3 JND of ΔE*ab.
SHADING_MISFIT_DE = 3 * JND_CIE76
#: Default QC limit on ΔE at each geometry (and on the mean under the "mean" rule), in the units of
#: the tolerance set's formula. A product default, not a standard's value: customers' tolerance sets
#: state their own (station.qc.tolerance).
QC_DE_LIMIT = 1.0
#: Default warn band of QC verdicts: "warn" once a value exceeds this fraction of its limit.
QC_WARN_FRACTION = 0.8
#: Accepted range of a QC warn fraction (exclusive lower, inclusive upper bound: 1 turns the band off).
QC_WARN_FRACTION_RANGE: tuple[float, float] = (0.0, 1.0)
#: Default aggregation rule of a QC verdict over the geometries.
QC_AGGREGATION = "max"
#: Default colour-difference formula of a QC tolerance set.
QC_FORMULA = "din6175"
#: Repeat readings: a reading is an outlier when the robust z of its ΔE*ab to the median reading
#: exceeds this (Iglewicz & Hoaglin's modified z-score threshold, 3.5; station.qc.repeats).
QC_OUTLIER_Z = 3.5
#: Floor of the robust scale (1.4826 × MAD) of repeat readings, ΔE*ab: keeps the z finite when most
#: readings coincide; about an instrument's short-term repeatability.
QC_OUTLIER_SCALE_FLOOR = 0.02
#: SPC control limits of ΔE: centre ± this many σ (station.qc.spc).
QC_SPC_SIGMAS = 3.0
