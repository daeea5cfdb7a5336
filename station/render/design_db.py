"""The design database over which the lobe basis is chosen and the fitters are benchmarked (eq 2.3.4).

Thesis §2.3.2: "About thirty different paints were chosen to express the range of BRDFs that can be
designed." Ours holds 40 face/flop/travel/gloss designs, deterministic (no random numbers):

* 8 solids (white, black, greys, saturated red/blue/yellow/green), gloss 5–95 GU;
* 8 silvers and greys with travel (bright aluminium flakes: L*15 up to 135, flop L* 25–60);
* 12 coloured metallics, including high travel (θ_clamp 120–170°) and dark flops;
* 8 hue-shifting pearls and interference colours (face and flop hues 40–170° apart);
* 4 extremes used by the stability tests: near-black metallic, very high gloss, extreme travel (180°),
  travel just above the face angle (16°).

Every design stays inside the sRGB gamut (no negative linear channel) over 0–180° aspecular, which
:func:`design_database` checks, so fit errors measure the basis and not gamut clipping.
"""

from __future__ import annotations

from functools import lru_cache
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from station.model import FaceFlopTravelGloss

#: The design classes of the module docstring, in table order, and how many rows each holds.
CLASSES: tuple[tuple[str, int], ...] = (
    ("solid", 8),
    ("silver", 8),
    ("metallic", 12),
    ("pearl", 8),
    ("extreme", 4),
)

#: name, face Lab, flop Lab, travel (deg, None = solid), gloss GU.
_ROWS: tuple[tuple[str, tuple[float, float, float], tuple[float, float, float], float | None, float], ...] = (
    # solids
    ("solid-white", (94.0, -0.5, 2.0), (94.0, -0.5, 2.0), None, 90.0),
    ("solid-black", (3.0, 0.0, -0.5), (3.0, 0.0, -0.5), None, 95.0),
    ("solid-mid-grey", (52.0, 0.0, 0.0), (52.0, 0.0, 0.0), None, 60.0),
    ("solid-red", (42.0, 58.0, 38.0), (42.0, 58.0, 38.0), None, 88.0),
    ("solid-blue", (30.0, 12.0, -45.0), (30.0, 12.0, -45.0), None, 85.0),
    ("solid-yellow", (82.0, 2.0, 75.0), (82.0, 2.0, 75.0), None, 70.0),
    ("solid-green-matte", (48.0, -38.0, 18.0), (48.0, -38.0, 18.0), None, 5.0),
    ("solid-grey-satin", (65.0, -1.0, 3.0), (65.0, -1.0, 3.0), None, 30.0),
    # silvers and greys with travel
    ("silver-bright", (135.0, -0.5, -1.5), (28.0, 0.0, -2.0), 110.0, 90.0),
    ("silver-classic", (118.0, -0.8, 0.5), (38.0, -0.5, -1.0), 95.0, 88.0),
    ("silver-fine", (100.0, -0.3, -0.8), (55.0, -0.3, -1.5), 80.0, 85.0),
    ("silver-liquid", (132.0, 0.0, 1.0), (25.0, 0.5, 0.0), 150.0, 92.0),
    ("gunmetal", (72.0, -0.5, -2.5), (22.0, 0.0, -2.0), 110.0, 85.0),
    ("champagne", (110.0, 1.5, 12.0), (52.0, 2.5, 10.0), 100.0, 80.0),
    ("silver-low-gloss", (108.0, 0.0, 0.0), (45.0, 0.0, 0.0), 110.0, 20.0),
    ("graphite-coarse", (60.0, 0.0, -1.0), (30.0, 0.0, -0.5), 60.0, 75.0),
    # coloured metallics
    ("blue-metallic", (52.0, -2.0, -42.0), (18.0, 8.0, -30.0), 110.0, 88.0),
    ("red-metallic", (46.0, 52.0, 28.0), (20.0, 40.0, 14.0), 100.0, 88.0),
    ("green-metallic", (50.0, -36.0, 8.0), (20.0, -17.0, 2.0), 105.0, 85.0),
    ("gold-metallic", (95.0, 6.0, 52.0), (45.0, 10.0, 32.0), 100.0, 85.0),
    ("bronze-metallic", (70.0, 14.0, 28.0), (28.0, 12.0, 16.0), 115.0, 80.0),
    ("copper-high-travel", (78.0, 26.0, 30.0), (22.0, 16.0, 10.0), 150.0, 88.0),
    ("teal-high-travel", (66.0, -26.0, -16.0), (18.0, -10.0, -8.0), 165.0, 90.0),
    ("wine-metallic", (34.0, 38.0, 8.0), (12.0, 22.0, 2.0), 120.0, 86.0),
    ("navy-dark-flop", (30.0, 4.0, -32.0), (6.0, 3.0, -10.0), 110.0, 88.0),
    ("orange-metallic", (72.0, 38.0, 58.0), (40.0, 34.0, 36.0), 90.0, 60.0),
    ("purple-metallic", (42.0, 34.0, -34.0), (18.0, 20.0, -20.0), 110.0, 45.0),
    ("yellow-metallic-matte", (88.0, -2.0, 62.0), (55.0, 0.0, 42.0), 100.0, 10.0),
    # hue-shifting pearls and interference colours
    ("pearl-white", (98.0, -2.0, 6.0), (88.0, 1.0, -3.0), 75.0, 88.0),
    ("pearl-green-to-blue", (70.0, -30.0, 12.0), (38.0, -10.0, -24.0), 110.0, 88.0),
    ("pearl-gold-to-red", (82.0, 6.0, 48.0), (40.0, 32.0, 18.0), 110.0, 88.0),
    ("pearl-blue-to-violet", (58.0, -2.0, -30.0), (30.0, 22.0, -26.0), 100.0, 85.0),
    ("pearl-red-to-gold", (45.0, 45.0, 20.0), (42.0, 12.0, 34.0), 90.0, 80.0),
    ("chroma-green-purple", (64.0, -30.0, 14.0), (28.0, 28.0, -22.0), 120.0, 90.0),
    ("chroma-cyan-magenta", (72.0, -14.0, -16.0), (30.0, 30.0, -12.0), 100.0, 92.0),
    ("pearl-silk-low-gloss", (90.0, 4.0, 10.0), (70.0, -2.0, 2.0), 80.0, 15.0),
    # extremes (also used by the stability tests)
    ("extreme-near-black-metallic", (8.0, 0.5, -1.0), (1.0, 0.2, -0.4), 110.0, 95.0),
    ("extreme-gloss-95", (55.0, 0.0, -30.0), (25.0, 4.0, -22.0), 110.0, 95.0),
    ("extreme-travel-180", (120.0, 0.0, 0.0), (20.0, 0.0, 0.0), 180.0, 88.0),
    ("extreme-travel-16", (80.0, 0.0, 0.0), (40.0, 0.0, 0.0), 16.0, 5.0),
)


@lru_cache(maxsize=1)
def design_database() -> tuple[FaceFlopTravelGloss, ...]:
    """Return the 40 designs of the module docstring (deterministic, gamut-checked)."""
    import numpy as np

    from station.model import FaceFlopTravelGloss
    from station.model.colorimetry import lab_to_linear_srgb

    designs = tuple(
        FaceFlopTravelGloss(face, flop, travel, gloss, name) for name, face, flop, travel, gloss in _ROWS
    )
    angles = np.linspace(0.0, 180.0, 181)
    for d in designs:
        rgb = lab_to_linear_srgb(d.lab_at(angles))
        if np.any(rgb < -1e-9):  # a programming error in the table above, never user input
            raise AssertionError(f"design database entry {d.name!r} leaves the sRGB gamut")
    return designs


def design_classes() -> dict[str, tuple[int, ...]]:
    """Indices into :func:`design_database` of each class of the module docstring (CLASSES order)."""
    out: dict[str, tuple[int, ...]] = {}
    start = 0
    for name, count in CLASSES:
        out[name] = tuple(range(start, start + count))
        start += count
    if start != len(_ROWS):  # a programming error in the tables above
        raise AssertionError("design_db.CLASSES does not cover the design table")
    return out
