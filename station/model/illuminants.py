"""The light-booth illuminant catalogue, user SPD files and the CIE observers (colour-science's data).

Booth illuminants are named as a paint lab names them: ``D65``, ``D50``, ``A``, ``F2``, ``F11`` (sold as
``TL84`` in booths: an alias of the same spectrum), ``LED-B3`` and ``LED-B4`` (CIE 15:2018 LED
illuminants). Their spectral power distributions are colour-science's (``colour.SDS_ILLUMINANTS``),
never copied here. A user's own lamp is an :class:`Illuminant` read from a CSV file of
``wavelength_nm,value`` rows by :func:`read_spd_file`; it must cover 400–700 nm (the product's
reflectance grid, :data:`station.model.spectra.WAVELENGTHS`) with positive, finite values.

Observers are the CIE 1931 2° and CIE 1964 10° standard observers, named by their colour-science names;
``"2"`` and ``"10"`` are accepted short forms (:func:`observer_cie_name`).
"""

from __future__ import annotations

import csv
import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from types import MappingProxyType
from typing import TYPE_CHECKING, Final

from station.model.colorimetry import OBSERVER_10
from station.model.domain import BOOTH_ILLUMINANTS, REFERENCE_ILLUMINANT
from station.model.errors import ModelInputError

if TYPE_CHECKING:  # colour-science (about a second) is imported by the functions that use it
    import colour

__all__ = [
    "BOOTH_ILLUMINANTS",
    "ILLUMINANT_ALIASES",
    "OBSERVERS",
    "OBSERVER_2",
    "REFERENCE_ILLUMINANT",
    "SPD_RANGE_NM",
    "Illuminant",
    "SpdFileError",
    "booth_illuminant",
    "illuminant_from_spd",
    "illuminant_from_text",
    "illuminant_name",
    "illuminant_sd",
    "observer_cie_name",
    "read_spd_file",
]

#: The CIE 1931 2° standard observer (colour-science's name).
OBSERVER_2: Final = "CIE 1931 2 Degree Standard Observer"
#: Observers offered, short form → colour-science name.
OBSERVERS: Final = MappingProxyType({"2": OBSERVER_2, "10": OBSERVER_10})
#: Booth names → colour-science's names (F-series lamps are "FL" there; TL84 is sold as F11's lamp).
ILLUMINANT_ALIASES: Final = MappingProxyType(
    {"F2": "FL2", "F7": "FL7", "F11": "FL11", "TL84": "FL11", "FL2": "FL2", "FL11": "FL11"}
)
#: Wavelength range (nm) a user SPD must cover: the product's reflectance grid.
SPD_RANGE_NM: Final = (400.0, 700.0)


class SpdFileError(ModelInputError):
    """A user SPD file cannot be used; the message names the file, the field and the accepted range."""

    def __init__(self, path: str | Path, field: str, accepted: str, got: object) -> None:
        super().__init__(f"{path}: {field}", accepted, got)


@dataclass(frozen=True)
class Illuminant:
    """A light source by its relative spectral power distribution (hashable: it keys cached weights).

    Parameters
    ----------
    name
        Display name (a catalogue name, or the user file's stem).
    wavelengths_nm
        Strictly increasing wavelengths in nm.
    values
        Relative spectral power at each wavelength (arbitrary scale; positive).
    """

    name: str
    wavelengths_nm: tuple[float, ...]
    values: tuple[float, ...]

    def sd(self) -> colour.SpectralDistribution:
        """The colour-science spectral distribution, interpolated linearly as colour's illuminants are."""
        import colour

        return colour.SpectralDistribution(
            dict(zip(self.wavelengths_nm, self.values, strict=True)),
            name=self.name,
            interpolator=colour.LinearInterpolator,
        )


def illuminant_name(name: str) -> str:
    """Catalogue name of *name* (case-insensitive; e.g. ``"tl84"`` → ``"TL84"``).

    Raises
    ------
    ModelInputError
        *name* is not a booth illuminant nor one of colour-science's illuminants.
    """
    text = str(name).strip()
    for known in BOOTH_ILLUMINANTS:
        if text.upper() == known.upper():
            return known
    import colour

    if text in colour.SDS_ILLUMINANTS:
        return text
    raise ModelInputError(
        "illuminant", f"one of {', '.join(BOOTH_ILLUMINANTS)} or a user SPD file (.csv)", name
    )


def booth_illuminant(name: str) -> Illuminant:
    """The catalogue illuminant *name* as an :class:`Illuminant` (colour-science's SPD)."""
    import colour

    canonical = illuminant_name(name)
    sd = colour.SDS_ILLUMINANTS[ILLUMINANT_ALIASES.get(canonical, canonical)]
    return Illuminant(canonical, tuple(float(w) for w in sd.wavelengths), tuple(float(v) for v in sd.values))


def illuminant_sd(illuminant: str | Illuminant) -> tuple[str, colour.SpectralDistribution]:
    """``(name, colour-science SPD)`` of a catalogue name or an :class:`Illuminant`."""
    import colour

    if isinstance(illuminant, Illuminant):
        return illuminant.name, illuminant.sd()
    canonical = illuminant_name(illuminant)
    return canonical, colour.SDS_ILLUMINANTS[ILLUMINANT_ALIASES.get(canonical, canonical)]


def observer_cie_name(observer: str | int) -> str:
    """colour-science name of an observer given as ``2``, ``"10"``, ``"10°"`` or its full name."""
    text = str(observer).strip()
    if text in OBSERVERS.values():
        return text
    short = text.removesuffix("_Degree").removesuffix("°").removesuffix("deg").strip()
    if short in OBSERVERS:
        return OBSERVERS[short]
    raise ModelInputError(
        "observer", f"one of {', '.join(OBSERVERS)} (degrees) or {', '.join(OBSERVERS.values())}", observer
    )


def read_spd_file(path: str | Path, name: str | None = None) -> Illuminant:
    """Read a user illuminant from a CSV file of ``wavelength_nm,value`` rows.

    A header row (non-numeric first cell) and ``#`` comment lines are skipped. The wavelengths must be
    strictly increasing and cover :data:`SPD_RANGE_NM` (400–700 nm); every value finite and > 0.

    Raises
    ------
    SpdFileError
        The file is unreadable or a row, the wavelengths or the values are out of range; the message
        names the file and the field.
    """
    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8-sig")
    except (OSError, UnicodeDecodeError) as exc:
        raise SpdFileError(p, "file", "a readable UTF-8 CSV file", type(exc).__name__) from exc
    wavelengths: list[float] = []
    values: list[float] = []
    rows = [
        r
        for r in csv.reader(
            line for line in text.splitlines() if line.strip() and not line.lstrip().startswith("#")
        )
    ]
    for i, row in enumerate(rows, start=1):
        cells = [c.strip() for c in row if c.strip()]
        if len(cells) != 2:
            raise SpdFileError(p, f"row {i}", "two cells: wavelength_nm,value", row)
        try:
            w, v = float(cells[0]), float(cells[1])
        except ValueError as exc:
            if i == 1 and not wavelengths:
                continue  # a header row
            raise SpdFileError(p, f"row {i}", "two numbers: wavelength_nm,value", row) from exc
        if not math.isfinite(w) or (wavelengths and w <= wavelengths[-1]):
            raise SpdFileError(
                p, f"row {i}: wavelength_nm", "finite wavelengths, strictly increasing", cells[0]
            )
        if not math.isfinite(v) or v <= 0.0:
            raise SpdFileError(p, f"row {i}: value", "a finite spectral power > 0", cells[1])
        wavelengths.append(w)
        values.append(v)
    short = _range_short(wavelengths)
    if short is not None:
        raise SpdFileError(p, "wavelength_nm", _RANGE_ACCEPTED, short)
    return Illuminant(name or p.stem, tuple(wavelengths), tuple(values))


_RANGE_ACCEPTED = f"a range covering {SPD_RANGE_NM[0]:g}–{SPD_RANGE_NM[1]:g} nm"


def _range_short(wavelengths: Sequence[float]) -> str | None:
    """None when *wavelengths* cover :data:`SPD_RANGE_NM`, else what they do cover (for the message)."""
    lo, hi = SPD_RANGE_NM
    if len(wavelengths) >= 2 and wavelengths[0] <= lo and wavelengths[-1] >= hi:
        return None
    return f"{wavelengths[0]:g}–{wavelengths[-1]:g} nm" if wavelengths else "no values"


def illuminant_from_spd(
    name: str, wavelengths_nm: Sequence[float], values: Sequence[float], field: str = "illuminant"
) -> Illuminant:
    """A user :class:`Illuminant` from arrays (a service body), validated like :func:`read_spd_file`.

    Raises
    ------
    ModelInputError
        Naming ``FIELD.name``, ``FIELD.wavelengths_nm`` or ``FIELD.values``: an empty name or one that
        shadows a catalogue illuminant, wavelengths not strictly increasing or not covering 400–700 nm,
        a value not finite and > 0, or lengths that differ.
    """
    label = str(name).strip()
    if not label:
        raise ModelInputError(f"{field}.name", "a non-empty name", name)
    if any(label.upper() == known.upper() for known in BOOTH_ILLUMINANTS):
        raise ModelInputError(f"{field}.name", "a name that is not a catalogue illuminant", name)
    wl = [float(w) for w in wavelengths_nm]
    vals = [float(v) for v in values]
    if len(wl) != len(vals):
        raise ModelInputError(f"{field}.values", f"{len(wl)} values (one per wavelength)", len(vals))
    for i in range(len(wl)):
        if not math.isfinite(wl[i]) or (i and wl[i] <= wl[i - 1]):
            raise ModelInputError(
                f"{field}.wavelengths_nm[{i}]", "finite wavelengths, strictly increasing", wl[i]
            )
        if not math.isfinite(vals[i]) or vals[i] <= 0.0:
            raise ModelInputError(f"{field}.values[{i}]", "a finite spectral power > 0", vals[i])
    short = _range_short(wl)
    if short is not None:
        raise ModelInputError(f"{field}.wavelengths_nm", _RANGE_ACCEPTED, short)
    return Illuminant(label, tuple(wl), tuple(vals))


def illuminant_from_text(text: str, allow_files: bool = True) -> str | Illuminant:
    """A catalogue name (canonical spelling) or, with *allow_files*, a user SPD file path (``*.csv``).

    Raises
    ------
    ModelInputError
        Neither a known illuminant nor (when allowed) a readable SPD file; :class:`SpdFileError` for a
        bad file.
    """
    t = str(text).strip()
    try:
        return illuminant_name(t)
    except ModelInputError:
        if allow_files and t.lower().endswith(".csv"):
            return read_spd_file(t)
        raise
