"""Colour libraries: multi-angle Lab + gloss per paint code, the thesis's hierarchy and browser filters.

A :class:`Library` holds N paints measured (or predicted) at the same aspecular angles (degrees,
illumination at 45°, D65 / CIE 1964 10°), one 60° gloss value each, a type (solid, metallic, pearl) and,
for libraries generated from the colorant model, the recipe of each paint. It is a plain value: no
database, no files; :mod:`station.formulate.library_csv` and :mod:`station.formulate.cxf` read and write it.

Hierarchy (thesis §5.3.3, Fig. 5.3): solids | metallics+pearls → chromatic (blue, green, yellow, red) |
neutral (light, medium, dark). The thesis names the groups but not the boundaries; ours are stated in
:func:`classify` and use the 45° Lab (the one angle shared by every instrument set).

Filters (thesis §5.3.3, "Search interface"): type check boxes and lower/upper bounds on the Flop Index
(eq 5.3.1), Chroma Index (eq 5.3.2) and Hue Shift Index (eq 5.3.3), computed by
:func:`station.model.indices.library_indices`.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from types import MappingProxyType

import numpy as np

from station.formulate.errors import FormulateInputError
from station.model.domain import ANGLES_3, PAINT_TYPES

#: The angles every library row holds: the standard 3-angle set of station.model.domain.
STANDARD_ANGLES: tuple[float, ...] = ANGLES_3

#: Chroma C*ab at 45° below which a paint is neutral (ΔE*ab units).
NEUTRAL_CHROMA = 10.0
#: L* at 45° bounds of the neutral value groups: dark < 35 <= medium < 65 <= light.
NEUTRAL_L_BOUNDS = (35.0, 65.0)
#: Hue-angle sectors (degrees, h_ab at 45°) of the chromatic groups; red wraps through 0°.
HUE_SECTORS: Mapping[str, tuple[float, float]] = MappingProxyType(
    {
        "red": (315.0, 55.0),
        "yellow": (55.0, 125.0),
        "green": (125.0, 195.0),
        "blue": (195.0, 315.0),
    }
)


@dataclass(frozen=True)
class Paint:
    """One library paint: ``lab`` has one (L*, a*, b*) triple per angle of ``angles_deg`` (degrees)."""

    code: str
    type: str
    gloss_gu: float
    angles_deg: tuple[float, ...]
    lab: tuple[tuple[float, float, float], ...]
    recipe: dict[str, float] | None = None
    group: tuple[str, str, str] = ("", "", "")

    def lab_at(self, angle_deg: float) -> tuple[float, float, float]:
        """Return the Lab triple measured at *angle_deg* (degrees); the angle must be in the paint's set."""
        try:
            return self.lab[self.angles_deg.index(float(angle_deg))]
        except ValueError as exc:
            raise FormulateInputError("angle_deg", f"one of {self.angles_deg}", angle_deg) from exc


@dataclass
class Library:
    """N paints at shared aspecular angles.

    Attributes
    ----------
    name
        Display name, e.g. ``"demo (synthetic)"``.
    codes, types
        ``(N,)`` string arrays; codes are unique.
    gloss_gu
        ``(N,)`` 60° gloss in GU.
    angles_deg
        Aspecular angles (degrees) of the Lab columns; always contains 15, 45 and 110.
    lab
        ``(N, len(angles_deg), 3)`` CIE L*a*b* (D65, 10°).
    synthetic
        True when the paints are generated (the demo library); every front must say so.
    recipes, colorant_names
        ``(N, n_colorants)`` mass fractions and the colorant names, or ``None`` for measured libraries.
    """

    name: str
    codes: np.ndarray
    types: np.ndarray
    gloss_gu: np.ndarray
    angles_deg: tuple[float, ...]
    lab: np.ndarray
    synthetic: bool = False
    recipes: np.ndarray | None = None
    colorant_names: tuple[str, ...] | None = None
    source: str = ""
    _indices: dict[str, np.ndarray] | None = field(default=None, repr=False, compare=False)
    _code_index: dict[str, int] | None = field(default=None, repr=False, compare=False)

    def __post_init__(self) -> None:
        self.codes = np.asarray(self.codes, dtype=str)
        self.types = np.asarray(self.types, dtype=str)
        self.gloss_gu = np.asarray(self.gloss_gu, dtype=np.float64)
        self.lab = np.asarray(self.lab, dtype=np.float64)
        self.angles_deg = tuple(float(a) for a in self.angles_deg)
        n = self.codes.shape[0]
        if self.lab.shape != (n, len(self.angles_deg), 3):
            raise FormulateInputError(
                "lab", f"shape (N={n}, {len(self.angles_deg)} angles, 3)", self.lab.shape
            )
        if self.types.shape != (n,) or self.gloss_gu.shape != (n,):
            raise FormulateInputError(
                "types/gloss_gu", f"shape ({n},)", (self.types.shape, self.gloss_gu.shape)
            )
        for a in STANDARD_ANGLES:
            if a not in self.angles_deg:
                raise FormulateInputError("angles_deg", "a set containing 15, 45 and 110", self.angles_deg)
        if self.recipes is not None:
            self.recipes = np.asarray(self.recipes, dtype=np.float64)
            if self.colorant_names is None or self.recipes.shape != (n, len(self.colorant_names)):
                raise FormulateInputError("recipes", "(N, len(colorant_names)) with colorant names", None)

    def __len__(self) -> int:
        return int(self.codes.shape[0])

    # -- access ---------------------------------------------------------------------------------------
    def angle_columns(self, angles_deg: tuple[float, ...] = STANDARD_ANGLES) -> np.ndarray:
        """Return the ``(N, len(angles_deg), 3)`` Lab at *angles_deg* (each must be in the library's set)."""
        try:
            idx = [self.angles_deg.index(float(a)) for a in angles_deg]
        except ValueError as exc:
            raise FormulateInputError("angles_deg", f"a subset of {self.angles_deg}", angles_deg) from exc
        return self.lab[:, idx, :]

    def index_of(self, code: str) -> int:
        """Return the row of paint *code*; raises :class:`FormulateInputError` if absent."""
        if self._code_index is None:
            self._code_index = {str(c): i for i, c in enumerate(self.codes)}
        try:
            return self._code_index[code]
        except KeyError as exc:
            raise FormulateInputError("code", f"a paint code of library {self.name!r}", code) from exc

    def paint(self, i: int) -> Paint:
        """Return paint row *i* as a :class:`Paint`."""
        recipe = None
        if self.recipes is not None and self.colorant_names is not None:
            recipe = {n: float(c) for n, c in zip(self.colorant_names, self.recipes[i], strict=True) if c > 0}
        paint_set, kind, group = (
            str(g[0]) for g in classify(self.types[i : i + 1], self.angle_columns((45.0,))[i : i + 1, 0])
        )
        return Paint(
            code=str(self.codes[i]),
            type=str(self.types[i]),
            gloss_gu=float(self.gloss_gu[i]),
            angles_deg=self.angles_deg,
            lab=tuple((float(L), float(a), float(b)) for L, a, b in self.lab[i]),
            recipe=recipe,
            group=(paint_set, kind, group),
        )

    def subset(self, mask: np.ndarray, name: str | None = None) -> Library:
        """Return the paints where boolean *mask* (or integer rows) selects them, as a new library."""
        sel = np.asarray(mask)
        return Library(
            name=name or self.name,
            codes=self.codes[sel],
            types=self.types[sel],
            gloss_gu=self.gloss_gu[sel],
            angles_deg=self.angles_deg,
            lab=self.lab[sel],
            synthetic=self.synthetic,
            recipes=None if self.recipes is None else self.recipes[sel],
            colorant_names=self.colorant_names,
            source=self.source,
        )

    # -- hierarchy and indices ---------------------------------------------------------------------
    def groups(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Return the hierarchy of every paint: (set, kind, group) string arrays, see :func:`classify`."""
        return classify(self.types, self.angle_columns((45.0,))[:, 0])

    def indices(self) -> dict[str, np.ndarray]:
        """Return Flop / Chroma / Hue Shift Index arrays (eqs 5.3.1–5.3.3); NaN marks "undefined here".

        NaN is used only inside this mask-building table (the index function reports ``None`` where
        its formula fails: dark colours, L15 < L110, achromatic face); it never leaves as a result.
        """
        if self._indices is None:
            from station.model.indices import library_indices

            std = self.angle_columns(STANDARD_ANGLES)
            out = {k: np.full(len(self), np.nan) for k in ("flop", "chroma", "hue_shift")}
            for i in range(len(self)):
                r = library_indices(std[i, 0], std[i, 1], std[i, 2])
                for key, val in (
                    ("flop", r.flop_index),
                    ("chroma", r.chroma_index),
                    ("hue_shift", r.hue_shift_index),
                ):
                    if val is not None:
                        out[key][i] = float(val)
            self._indices = out
        return self._indices


def classify(types: np.ndarray, lab45: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Place paints in the thesis hierarchy (§5.3.3, Fig. 5.3).

    Parameters
    ----------
    types
        ``(N,)`` of ``"solid" | "metallic" | "pearl"``.
    lab45
        ``(N, 3)`` L*a*b* at 45° aspecular.

    Returns
    -------
    (set, kind, group)
        set ∈ {"solids", "metallics+pearls"}; kind ∈ {"chromatic", "neutral"};
        group ∈ {"blue", "green", "yellow", "red"} for chromatic (hue sectors :data:`HUE_SECTORS`),
        {"light", "medium", "dark"} for neutral (C*ab < :data:`NEUTRAL_CHROMA`, L* bounds
        :data:`NEUTRAL_L_BOUNDS`).
    """
    types = np.asarray(types, dtype=str)
    lab45 = np.asarray(lab45, dtype=np.float64).reshape(-1, 3)
    top = np.where(types == "solid", "solids", "metallics+pearls")
    chroma = np.hypot(lab45[:, 1], lab45[:, 2])
    neutral = chroma < NEUTRAL_CHROMA
    kind = np.where(neutral, "neutral", "chromatic")
    hue = np.degrees(np.arctan2(lab45[:, 2], lab45[:, 1])) % 360.0
    group = np.empty(len(types), dtype=object)
    for name, (lo, hi) in HUE_SECTORS.items():
        sel = (hue >= lo) & (hue < hi) if lo < hi else (hue >= lo) | (hue < hi)
        group[sel] = name
    lo_l, hi_l = NEUTRAL_L_BOUNDS
    value = np.where(lab45[:, 0] < lo_l, "dark", np.where(lab45[:, 0] < hi_l, "medium", "light"))
    group = np.where(neutral, value, group).astype(str)
    return top.astype(str), kind.astype(str), group


@dataclass(frozen=True)
class LibraryFilter:
    """Browser filter (thesis §5.3.3): type check boxes, index bounds and an optional hierarchy path.

    Bounds are inclusive; ``None`` leaves a side open. A paint whose index is undefined (the index
    function returned ``None``: a dark colour for the Flop Index, an achromatic face for the Hue Shift
    Index) passes only when both bounds of that index are open.
    """

    types: frozenset[str] = frozenset(PAINT_TYPES)
    flop: tuple[float | None, float | None] = (None, None)
    chroma: tuple[float | None, float | None] = (None, None)
    hue_shift: tuple[float | None, float | None] = (None, None)
    set_name: str | None = None
    kind: str | None = None
    group: str | None = None

    def __post_init__(self) -> None:
        bad = set(self.types) - set(PAINT_TYPES)
        if bad:
            raise FormulateInputError("types", f"a subset of {PAINT_TYPES}", sorted(bad))
        for name in ("flop", "chroma", "hue_shift"):
            lo, hi = getattr(self, name)
            for v in (lo, hi):
                if v is not None and not math.isfinite(v):
                    raise FormulateInputError(name, "finite bounds or None", v)
            if lo is not None and hi is not None and lo > hi:
                raise FormulateInputError(name, "lower bound <= upper bound", (lo, hi))

    def mask(self, library: Library) -> np.ndarray:
        """Return the boolean ``(N,)`` mask of the paints of *library* this filter keeps."""
        keep = np.isin(library.types, sorted(self.types))
        if self.set_name or self.kind or self.group:
            top, kind, group = library.groups()
            if self.set_name:
                keep &= top == self.set_name
            if self.kind:
                keep &= kind == self.kind
            if self.group:
                keep &= group == self.group
        if any(b != (None, None) for b in (self.flop, self.chroma, self.hue_shift)):
            idx = library.indices()
            for name in ("flop", "chroma", "hue_shift"):
                lo, hi = getattr(self, name)
                if lo is None and hi is None:
                    continue
                vals = idx[name]
                ok = np.isfinite(vals)
                if lo is not None:
                    ok &= np.where(ok, vals, 0.0) >= lo
                if hi is not None:
                    ok &= np.where(ok, vals, 0.0) <= hi
                keep &= ok
        return keep

    def apply(self, library: Library) -> Library:
        """Return the paints of *library* this filter keeps."""
        return library.subset(self.mask(library))


def hierarchy_counts(library: Library) -> dict[str, dict[str, dict[str, int]]]:
    """Return ``{set: {kind: {group: count}}}`` for the browser tree (thesis Fig. 5.3)."""
    top, kind, group = library.groups()
    out: dict[str, dict[str, dict[str, int]]] = {}
    for s in ("solids", "metallics+pearls"):
        out[s] = {"chromatic": {}, "neutral": {}}
        for g in ("blue", "green", "yellow", "red"):
            out[s]["chromatic"][g] = int(np.sum((top == s) & (kind == "chromatic") & (group == g)))
        for g in ("light", "medium", "dark"):
            out[s]["neutral"][g] = int(np.sum((top == s) & (kind == "neutral") & (group == g)))
    return out
