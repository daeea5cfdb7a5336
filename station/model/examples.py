"""Named example designs used by the docs, demos and tests of other packages.

Values are plausible automotive paints (not measurements of any product): a solid, a silver, a red
metallic and a hue-shifting pearl, all at 60° gloss near 88 GU as clear-coated panels read.
"""

from __future__ import annotations

from station.model.representations import FaceFlopTravelGloss

SOLID_WHITE = FaceFlopTravelGloss((92.0, -0.8, 2.5), (92.0, -0.8, 2.5), None, 88.0, "Solid white")
SILVER = FaceFlopTravelGloss((118.0, -0.9, -1.5), (28.0, -0.3, -2.8), 95.0, 90.0, "Silver metallic")
RED_METALLIC = FaceFlopTravelGloss((52.0, 48.0, 30.0), (12.0, 22.0, 9.0), 80.0, 88.0, "Red metallic")
HUE_SHIFT_PEARL = FaceFlopTravelGloss(
    (70.0, -22.0, -18.0), (38.0, 14.0, -34.0), 70.0, 86.0, "Blue-violet pearl"
)

#: The bright aluminium silver every package is tested on: L*15 = 125 (effect paints read 110–140 at
#: 15°, see station.model.domain), a dark flop L* 38, travel 65°, a glossy clear coat at 90 GU.
BRIGHT_SILVER = FaceFlopTravelGloss((125.0, -0.6, -1.8), (38.0, -0.3, -3.2), 65.0, 90.0, "Bright silver")

EXAMPLES: dict[str, FaceFlopTravelGloss] = {
    "solid": SOLID_WHITE,
    "silver": SILVER,
    "bright-silver": BRIGHT_SILVER,
    "red-metallic": RED_METALLIC,
    "pearl": HUE_SHIFT_PEARL,
}
