"""Colour palette entries (thesis §3.4.6): the gradient swatch and the shaded booklet thumbnail.

A palette file (schema ``cacad.palette/1``) is JSON: ``{"schema": "cacad.palette/1", "entries":
[{"name": …, "design": <cacad.design/1 object>}, …]}`` (:func:`save_palette` / :func:`load_palette`).

Both images are sRGB-encoded ``uint8`` arrays ``(H, W, 3)``; :func:`station.design.images.save_png` writes
them (Pillow, with an sRGB profile). Out-of-gamut colours are clipped *for display only*; the swatch
result reports how many columns were out of gamut so the clip is not hidden.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from station.design.errors import DesignInputError
from station.design.scene import panel_scene, shade, srgb_encode, to_uint8
from station.errors import InputError
from station.model import FaceFlopTravelGloss
from station.model.design_io import MAX_DESIGN_BYTES, design_from_dict, design_to_dict, read_json_file
from station.model.shading import design_reflectance

#: Aspecular range of the gradient bar, degrees (the standard angles 15° … 110°).
SWATCH_ANGLES = (15.0, 110.0)
#: Border brightness (sRGB-encoded grey) at 0 GU and at 100 GU.
BORDER_GREY = (0.15, 1.0)


@dataclass(frozen=True, eq=False)
class Swatch:
    """A palette swatch: pixels, the angle of each bar column and the out-of-gamut column count."""

    pixels: NDArray[np.uint8]
    angles_deg: NDArray[np.float64]
    out_of_gamut_columns: int


def border_grey(gloss_gu: float) -> float:
    """sRGB-encoded border grey for *gloss_gu*: linear from :data:`BORDER_GREY` [0] at 0 GU to [1] at 100 GU."""
    lo, hi = BORDER_GREY
    return lo + (hi - lo) * float(gloss_gu) / 100.0


def swatch(design: FaceFlopTravelGloss, width: int = 160, height: int = 32, border: int = 4) -> Swatch:
    """Gradient bar of *design* across aspecular angles 15° → 110° (left → right), framed by a border
    whose brightness shows the gloss (thesis §3.4.6)."""
    for name, v, lo in (("width", width, 8), ("height", height, 4), ("border", border, 1)):
        if not isinstance(v, (int, np.integer)) or not lo <= v <= 4096:
            raise DesignInputError(name, f"integer {lo}..4096 pixels", v)
    if 2 * border >= min(width, height):
        raise DesignInputError("border", f"< {min(width, height) // 2} pixels for this size", border)
    inner = width - 2 * border
    angles = np.linspace(*SWATCH_ANGLES, inner)
    rgb = design_reflectance(design, angles)
    oog = int(np.sum(np.any((rgb < -1e-6) | (rgb > 1 + 1e-6), axis=-1)))
    img = np.empty((height, width, 3))
    img[:] = border_grey(design.gloss_gu)
    img[border : height - border, border : width - border] = srgb_encode(rgb)[None, :, :]
    return Swatch(to_uint8(img), angles, oog)


def booklet(design: FaceFlopTravelGloss, size: int = 96) -> NDArray[np.uint8]:
    """Shaded booklet thumbnail (thesis Fig. 3.11): *design* on a bent panel under the default point light
    (:func:`station.design.scene.panel_scene`), on a mid-grey background, gloss highlight included."""
    scene = panel_scene(size)
    return to_uint8(srgb_encode(shade(scene, design, specular=True, background=(0.18, 0.18, 0.18))))


# ------------------------------------------------------------------------------------- palette files

PALETTE_SCHEMA = "cacad.palette/1"
#: Largest palette file accepted, bytes (a palette holds many designs; ten design files' worth).
MAX_PALETTE_BYTES = 10 * MAX_DESIGN_BYTES

PaletteEntries = list[tuple[str, FaceFlopTravelGloss]]


def palette_to_dict(entries: Sequence[tuple[str, FaceFlopTravelGloss]]) -> dict[str, Any]:
    """The ``cacad.palette/1`` JSON object of named designs (order kept)."""
    return {
        "schema": PALETTE_SCHEMA,
        "entries": [{"name": str(name), "design": design_to_dict(d)} for name, d in entries],
    }


def palette_from_dict(data: Any) -> PaletteEntries:
    """Parse a ``cacad.palette/1`` object; errors name the entry and the field."""
    if not isinstance(data, dict) or data.get("schema") != PALETTE_SCHEMA:
        got = data.get("schema") if isinstance(data, dict) else type(data).__name__
        raise DesignInputError("schema", f'"{PALETTE_SCHEMA}"', got)
    rows = data.get("entries")
    if not isinstance(rows, list):
        raise DesignInputError("entries", "a list of {name, design}", type(rows).__name__)
    out: PaletteEntries = []
    for i, row in enumerate(rows):
        if not isinstance(row, dict) or not isinstance(row.get("name"), str):
            raise DesignInputError(f"entries[{i}].name", "a string", row)
        try:
            design = design_from_dict(row.get("design"))
        except (InputError, ValueError) as exc:
            raise DesignInputError(f"entries[{i}].design", "a cacad.design/1 object", None, str(exc)) from exc
        out.append((row["name"], design))
    return out


def save_palette(entries: Sequence[tuple[str, FaceFlopTravelGloss]], path: str | Path) -> Path:
    """Write a palette file (``cacad.palette/1`` JSON); returns the path."""
    p = Path(path)
    p.write_text(json.dumps(palette_to_dict(entries), indent=2) + "\n", encoding="utf-8")
    return p


def load_palette(path: str | Path) -> PaletteEntries:
    """Read a palette file written by :func:`save_palette`; errors name the file or the field."""
    data = read_json_file(
        path, "palette", f"palette file ({PALETTE_SCHEMA})", MAX_PALETTE_BYTES, error=DesignInputError
    )
    return palette_from_dict(data)
