"""Fixtures of the colour-styling suite: small scenes and a few in-gamut designs."""

from __future__ import annotations

import pytest

from station.design.scene import Scene, sphere_scene
from station.model import FaceFlopTravelGloss


@pytest.fixture(scope="session")
def sphere() -> Scene:
    """A 64-pixel sphere under the default light (45° off the view axis)."""
    return sphere_scene(64)


@pytest.fixture(scope="session")
def red_metallic() -> FaceFlopTravelGloss:
    """A red metallic, in the sRGB gamut at every angle."""
    return FaceFlopTravelGloss((60.0, 30.0, 10.0), (25.0, 20.0, 15.0), 70.0, 50.0)


@pytest.fixture(scope="session")
def blue_metallic() -> FaceFlopTravelGloss:
    """A blue metallic with a long travel."""
    return FaceFlopTravelGloss((55.0, -20.0, -20.0), (30.0, -12.0, -18.0), 90.0, 50.0)


@pytest.fixture(scope="session")
def silver() -> FaceFlopTravelGloss:
    """The thesis's default starting colour for sketches: a neutral silver."""
    return FaceFlopTravelGloss((85.0, 0.0, 0.0), (40.0, 0.0, 0.0), 70.0, 50.0)
