"""The thesis's misalignment scenarios (§4.4, Figs 4.4–4.7) as reproducible functions.

The thesis gives the geometry of Fig. 4.4 (3° misalignment, point light at 0, 15.5, 29.1, 39.8, 45.0 and
52.0° from the normal) but not its paint colours, nor the geometries of Figs 4.5–4.7; the choices made
here are stated in each function and in docs/misalignment.md.
"""

from __future__ import annotations

from station.analysis.trompe import TrompeResult, inverse_trompe_loeil
from station.model import FaceFlopTravelGloss
from station.model.domain import ANGLES_5

#: Fig. 4.4 light directions, degrees from the normal.
SOLID_LIGHTS_DEG = (0.0, 15.5, 29.1, 39.8, 45.0, 52.0)
#: Fig. 4.4 misalignment, degrees (panel B turned away from the light).
SOLID_BETA_DEG = -3.0
#: Fig. 4.4 paint (not given in the thesis): a light blue-grey solid.
SOLID_PAINT = FaceFlopTravelGloss(
    (75.0, -5.0, -20.0), (75.0, -5.0, -20.0), None, name="light blue-grey solid"
)
#: Fig. 4.5: silver with a black flop, 2° misalignment.
SILVER_PAINT = FaceFlopTravelGloss((100.0, 0.0, 0.0), (5.0, 0.0, 0.0), 60.0, name="silver, black flop")
SILVER_BETA_DEG = -2.0
#: 5-angle instrument geometries under a 45° light: aspecular 15, 25, 45, 75, 110°.
INSTRUMENT_ASPECULAR = ANGLES_5
#: Figs 4.6–4.7: bumper / fender, 8° misalignment, a blue metallic.
BUMPER_PAINT = FaceFlopTravelGloss((60.0, -4.0, -42.0), (18.0, 2.0, -22.0), 55.0, name="blue metallic")
BUMPER_BETA_DEG = 8.0


def solid_panels(
    paint: FaceFlopTravelGloss = SOLID_PAINT, beta_deg: float = SOLID_BETA_DEG
) -> dict[str, TrompeResult]:
    """Fig. 4.4: the four columns (identical paint is ``seam_de_before``): 45°-optimised, RMS, per row.

    Also the minimax solution. Views from the normal (a solid's colour does not depend on the view).
    """
    lights = list(SOLID_LIGHTS_DEG)
    at45 = lights.index(45.0)
    return {
        "single_45": inverse_trompe_loeil(paint, lights, beta_deg=beta_deg, objective="single", at=at45),
        "rms": inverse_trompe_loeil(paint, lights, beta_deg=beta_deg, objective="rms"),
        "minimax": inverse_trompe_loeil(paint, lights, beta_deg=beta_deg, objective="minimax"),
        "per_geometry": inverse_trompe_loeil(paint, lights, beta_deg=beta_deg, objective="per_geometry"),
    }


def _instrument_geometries(light: float = 45.0) -> tuple[list[float], list[float]]:
    return [light] * len(INSTRUMENT_ASPECULAR), [a - light for a in INSTRUMENT_ASPECULAR]


def silver_black_flop(
    paint: FaceFlopTravelGloss = SILVER_PAINT, beta_deg: float = SILVER_BETA_DEG
) -> TrompeResult:
    """Fig. 4.5: face L* and travel only, RMS over the 5-angle geometries under a 45° light, in-plane."""
    ls, vs = _instrument_geometries()
    return inverse_trompe_loeil(paint, ls, vs, beta_deg=beta_deg, objective="rms", subset="face_L+travel")


def bumper_fender(
    paint: FaceFlopTravelGloss = BUMPER_PAINT, beta_deg: float = -BUMPER_BETA_DEG
) -> TrompeResult:
    """Figs 4.6–4.7: full FFTG, RMS over the 5-angle geometries under a 45° light, bumper turned away."""
    ls, vs = _instrument_geometries()
    return inverse_trompe_loeil(paint, ls, vs, beta_deg=beta_deg, objective="rms", subset="full")
