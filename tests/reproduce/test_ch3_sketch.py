"""§3.7: the sketch fit's RMS by an independent re-render; the contrast-gloss rule against art gloss."""

from __future__ import annotations

import numpy as np
import pytest

from station.design import artwork
from station.design.scene import shade, sphere_scene, srgb_encode
from station.design.sketch import fit_point_light
from station.reproduce import ch3_sketch as cs


def test_rerender_of_the_goal_design_itself_is_zero_and_a_wrong_gloss_is_not() -> None:
    scene = sphere_scene(cs.SIZE_PX)
    d = cs.DESIGNS[0]
    art = srgb_encode(shade(scene, d))
    assert cs.rerender_rms(cs.SIZE_PX, art, d) == pytest.approx(0.0, abs=1e-9)
    assert cs.rerender_rms(cs.SIZE_PX, art, d.replace(gloss_gu=5.0)) > 2.0


def test_fig320_case_within_the_thesis_and_above_the_fits_own_rms() -> None:
    scene = sphere_scene(cs.SIZE_PX)
    initial = srgb_encode(shade(scene, cs.INITIAL))
    art = artwork.rotate_hue(srgb_encode(shade(scene, cs.DESIGNS[1])), 90.0, scene.mask)
    fit = fit_point_light(scene, art, initial, gloss="contrast")
    independent = cs.rerender_rms(cs.SIZE_PX, art, fit.design)
    assert independent <= 2.0  # thesis: 2 ΔE
    assert independent > fit.rms_de + 0.5  # the highlight the fit leaves out (issue: 0.2 vs 1.6)


def test_contrast_gloss_falls_where_the_art_gloss_rises() -> None:
    scene = sphere_scene(cs.SIZE_PX)
    initial = srgb_encode(shade(scene, cs.DESIGNS[1]))
    read = [
        fit_point_light(
            scene, srgb_encode(shade(scene, cs.DESIGNS[0].replace(gloss_gu=g))), initial, gloss="contrast"
        ).design.gloss_gu
        for g in (50.0, 95.0)
    ]
    assert read[1] < read[0] - 5.0
    assert cs._decreases([1.0, 2.0, 1.0, 3.0, 2.9]) == 1


def test_environment_fit_is_fast_and_close() -> None:
    r = cs.environment_fit(None)
    assert all(q.verdict == "agrees" for q in r.quantities)
    t = r.quantities[0]
    assert t.ours < 1.0 and t.thesis == 120.0
    assert np.isfinite(r.quantities[2].ours) and r.quantities[2].ours < 5.0


def test_traced_art_fails_about_as_often_as_the_thesis_says() -> None:
    r = cs.traced_art(None)
    q = {x.quantity: x for x in r.quantities}
    assert q["traced art: re-render RMS (median of 12)"].ours <= 14.0  # thesis: 14 ΔE
    share = q["traced art: fits that fail on the first try"]
    assert abs(share.ours - 35.0) <= 10.0  # thesis: about 35 %
    assert share.verdict == "agrees"


def test_highlight_gloss_rises_with_the_art_gloss_and_reads_the_silver() -> None:
    """The experiment's sweep (5–95 GU art) read by the default gloss="highlight": no fall, within 3 GU from
    10 GU up, and the 90 GU silver the contrast rule read as 0 GU reads within 10 GU of 90."""
    read = cs.gloss_readings("highlight")
    assert cs._decreases(read, slack=0.0) == 0
    assert max(abs(r - a) for a, r in zip(cs.ART_GLOSS_GU, read, strict=True) if a >= 10.0) < 3.0
    assert abs(cs.silver_reading("highlight") - 90.0) <= 10.0
    assert cs.silver_reading("contrast") < 50.0  # the thesis's rule on the same art (the 0 GU)
