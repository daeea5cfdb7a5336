"""``FrameOptions`` checks its own fields when it is made (engine, prefilter engine, mesh and anisotropy on
the GL engine only), with typed errors naming the field and what is accepted; the level of detail's
``FrameProbe`` refuses the truth engine, which has none."""

from __future__ import annotations

import numpy as np
import pytest

from station.model import FaceFlopTravelGloss
from station.model.anisotropy import Anisotropy
from station.render.errors import RenderInputError
from station.render.meshes import Mesh
from station.render.procedural import procedural_environment
from station.render.scene_image import FrameOptions, FrameProbe
from station.render.shapes import Scene


def _triangle() -> Mesh:
    positions = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]], np.float32)
    normals = np.tile(np.array([0.0, 0.0, 1.0], np.float32), (3, 1))
    return Mesh("triangle", positions, normals, np.array([[0, 1, 2]], np.uint32), np.ones(3, np.float32))


@pytest.mark.parametrize(
    ("kwargs", "field", "accepted"),
    [
        ({"engine": "vulkan"}, "engine", "gl | numpy | truth"),
        ({"prefilter_engine": "truth"}, "prefilter_engine", "gl | numpy"),
        ({"engine": "numpy", "mesh": "triangle"}, "engine", "gl for a mesh"),
        ({"engine": "truth", "mesh": "triangle"}, "engine", "gl for a mesh"),
        ({"engine": "numpy", "anisotropy": (0.1, 0.3)}, "engine", "gl for a design with anisotropy"),
    ],
)
def test_bad_frame_options_name_the_field(kwargs: dict, field: str, accepted: str) -> None:
    given = dict(kwargs)
    if "mesh" in given:
        given["mesh"] = _triangle()
    if "anisotropy" in given:
        given["anisotropy"] = Anisotropy(*given["anisotropy"])
    with pytest.raises(RenderInputError) as err:
        FrameOptions(**given)
    assert err.value.field == field and err.value.accepted == accepted


def test_good_frame_options_and_the_probe_refusing_the_truth() -> None:
    assert FrameOptions("gl", "gl", mesh=_triangle(), anisotropy=Anisotropy(0.1, 0.3)).engine == "gl"
    truth = FrameOptions("truth")
    design = FaceFlopTravelGloss((60.0, 10.0, -40.0), (30.0, 5.0, -30.0), 60.0, 85.0)
    with pytest.raises(RenderInputError) as err:
        FrameProbe([design], procedural_environment("booth"), Scene("sphere"), truth)
    assert err.value.field == "engine" and "gl | numpy" in err.value.accepted
