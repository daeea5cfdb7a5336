"""The JSON forms every front prints or returns (``to_dict`` of the eyedrop, the variation ring and the
sketch fit), checked field by field against the result objects they come from."""

from __future__ import annotations

import json
import math

import numpy as np

from station.design.moodboard import EyedropResult, eyedrop_design
from station.design.scene import builtin_scene, shade, srgb_encode
from station.design.sketch import fit_point_light
from station.design.variations import variations
from station.model import FaceFlopTravelGloss
from station.model.design_io import design_from_dict

SILVER = FaceFlopTravelGloss((125.0, 0.0, 2.0), (40.0, 0.0, 1.0), 38.0, 90.0, "bright silver")


def _board() -> np.ndarray:
    """Left half light grey, right half dark grey, a white square (a highlight) in the light half."""
    img = np.empty((32, 32, 3))
    img[:, :16] = 0.8
    img[:, 16:] = 0.2
    img[4:8, 4:8] = 1.0
    return img


def test_eyedrop_dict_holds_the_result_and_the_extra_fields_before_gloss() -> None:
    r = eyedrop_design(_board(), (10, 20), (24, 20), gloss_xy=(6, 6), radius=1)
    d = json.loads(json.dumps(r.to_dict(colour="note")))
    assert list(d) == ["design", "face_lab", "flop_lab", "swapped", "colour", "gloss"]
    assert design_from_dict(d["design"]) == r.design
    assert d["face_lab"] == list(r.face_lab) and d["flop_lab"] == list(r.flop_lab)
    assert d["swapped"] is r.swapped and d["colour"] == "note"
    assert r.gloss is not None
    assert d["gloss"] == {
        "gloss_gu": r.gloss.gloss_gu,
        "contrast": r.gloss.contrast,
        "clipped": r.gloss.clipped,
    }


def test_eyedrop_dict_without_gloss_reading_has_no_gloss_key() -> None:
    r = EyedropResult(SILVER, (125.0, 0.0, 2.0), (40.0, 0.0, 1.0), False)
    assert "gloss" not in r.to_dict()


def test_ring_dict_lists_every_cell_in_ring_order() -> None:
    ring = variations(SILVER, 2.0, "face")
    d = json.loads(json.dumps(ring.to_dict()))
    assert design_from_dict(d["centre"]) == SILVER
    assert (d["category"], d["degree"]) == ("face", 2.0)
    assert [c["label"] for c in d["variations"]] == [v.label for v in ring.variations]
    for cell, v in zip(d["variations"], ring.variations, strict=True):
        assert cell["reason"] == v.reason
        assert (cell["design"] is None) == (v.design is None)
        if v.design is not None:
            assert design_from_dict(cell["design"]) == v.design


def test_sketch_fit_dict_is_plain_json_of_the_fit() -> None:
    scene = builtin_scene("sphere-point", 32)
    art = srgb_encode(shade(scene, SILVER))
    fit = fit_point_light(scene, art)
    d = fit.to_dict()
    assert json.loads(json.dumps(d)) == d  # plain Python numbers only
    assert design_from_dict(d["design"]) == fit.design
    assert d["lab_standard"]["lab"] == [[float(x) for x in v] for v in fit.lab_standard]
    assert d["pixels"] == fit.pixels and d["failed"] is fit.failed
    assert math.isclose(d["rms_de"], fit.rms_de, rel_tol=0.0, abs_tol=0.0) or math.isnan(fit.rms_de)
