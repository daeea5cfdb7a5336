"""A bright silver (L*15 125: a radiance factor above 1 near the specular) measured by every simulated
spectrophotometer, as a technician measures it: `station measure` from a user folder. The spectral
recovery behind the simulators reproduces such a face exactly (checked by colour-science's integration)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from simulators.physics import FULL_SCALE_L
from station.model import FaceFlopTravelGloss
from station.model.angles import flake_equivalent_aspecular
from station.model.design_io import save_design
from station.model.domain import parse_geometry
from station.model.errors import ModelInputError
from station.model.spectra import reflectance_from_lab, reflectance_to_lab
from tests.user_cli import run_station

BRIGHT = FaceFlopTravelGloss((125.0, 0.0, 0.0), (38.0, 0.0, 0.0), 70.0, 90.0, name="bright silver")


def test_recovery_reaches_a_face_above_diffuse_white() -> None:
    lab = BRIGHT.lab_at(np.array([15.0, 45.0, 110.0]))
    r = reflectance_from_lab(lab)
    assert r[0].max() > 1.0  # a radiance factor above 1 …
    np.testing.assert_allclose(reflectance_to_lab(r), lab, atol=1e-4)  # … that gives back the Lab
    with pytest.raises(ModelInputError, match="colour solid"):
        reflectance_from_lab([[50.0, 140.0, 0.0]])  # an object colour no reflectance in [0, 1] gives


@pytest.mark.parametrize("sim", ["ma6", "ma3"])
def test_simulators_measure_a_bright_silver(tmp_path, sim: str) -> None:
    save_design(BRIGHT, tmp_path / "bright.json")
    run = run_station(tmp_path, "measure", f"sim:{sim}", "--design", "bright.json", "--json", timeout=180)
    assert run.returncode == 0, run.stderr
    out = json.loads(run.stdout)
    angles = [parse_geometry(g)[1] for g in out["geometries"]]  # "45as15" → (45, 15)
    want = BRIGHT.lab_at(flake_equivalent_aspecular(angles))  # −15° lighter than +15° ...
    want[:, 0] = np.minimum(want[:, 0], FULL_SCALE_L)  # ... up to the detector's full scale
    assert np.max(np.abs(np.asarray(out["lab"]) - want)) < 1.0  # instrument noise, well under 1 ΔE
