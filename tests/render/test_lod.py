"""Level-of-detail choice: fewest lobes, smallest environment, fewest anisotropic samples for a tolerance."""

from __future__ import annotations

import numpy as np
import pytest
from numpy.typing import NDArray

from station.errors import InputError
from station.model import FaceFlopTravelGloss
from station.render import lod
from station.render import truth as tr

#: Normals and views of the test sphere, (P, 3) each.
Pixels = tuple[NDArray[np.float64], NDArray[np.float64]]


def sky(h: int = 64) -> np.ndarray:
    """Analytic sky gradient with a bright disc (built here, no files)."""
    d = tr.equirect_directions(h, 2 * h)
    img = np.where(d[..., 1:2] > 0, 0.5 + 1.0 * d[..., 1:2] * np.array([0.8, 0.9, 1.0]), 0.1)
    s = np.array([0.2, 0.6, 0.77])
    s /= np.linalg.norm(s)
    return img + (d @ s > np.cos(np.radians(6.0)))[..., None] * 30.0


@pytest.fixture(scope="module")
def metallic() -> FaceFlopTravelGloss:

    return FaceFlopTravelGloss((110.0, -1.0, -25.0), (30.0, 4.0, -20.0), 110.0, 85.0, "blue-silver")


@pytest.fixture(scope="module")
def pixels() -> Pixels:
    return tr.sphere_pixels(8)


def test_constant_environment_needs_the_least(metallic: FaceFlopTravelGloss, pixels: Pixels) -> None:
    choice = lod.choose_lod(
        [metallic],
        np.ones((32, 64, 3)),
        *pixels,
        tolerance_de=2.0,
        samples=32,
        quadrature_width=64,
        mode="prefiltered-lut",
    )
    assert choice.environment_width == 16  # a constant map survives any box filter
    assert choice.errors["environment"] == pytest.approx(0.0, abs=1e-6)
    assert choice.anisotropic_samples == 1
    assert choice.met and "lobes" in choice.describe()


def test_tighter_tolerance_never_chooses_less(metallic: FaceFlopTravelGloss, pixels: Pixels) -> None:
    loose = lod.choose_lod(
        [metallic], sky(), *pixels, tolerance_de=6.0, samples=32, quadrature_width=64, mode="exact"
    )
    tight = lod.choose_lod(
        [metallic], sky(), *pixels, tolerance_de=1.0, samples=32, quadrature_width=64, mode="exact"
    )
    assert tight.lobes >= loose.lobes
    assert tight.environment_width >= loose.environment_width
    share = 1.0 / np.sqrt(3.0)
    assert tight.errors["lobes"] <= share or not tight.met
    if tight.lobes > 1:  # the next smaller basis really misses the share (it was tried first)
        smaller = lod.choose_lod(
            [metallic],
            sky(),
            *pixels,
            tolerance_de=1.0,
            samples=32,
            quadrature_width=64,
            mode="exact",
            lobe_counts=[tight.lobes - 1],
        )
        assert smaller.errors["lobes"] > share


def test_anisotropic_samples_smallest_meeting_share(metallic: FaceFlopTravelGloss, pixels: Pixels) -> None:
    # The anisotropic renderer is the render helper's (station.render.anisotropy); this test drives the
    # selection with a stand-in whose error falls as 1/samples, so the answer is known in closed form.
    base = np.full((pixels[0].shape[0], 3), 0.2)

    def render(samples: int) -> np.ndarray:
        return base * (1.0 + 0.3 / samples)

    choice = lod.choose_lod(
        [metallic],
        np.ones((32, 64, 3)),
        *pixels,
        tolerance_de=3.0,
        samples=32,
        quadrature_width=64,
        anisotropic=render,
    )
    share = 3.0 / np.sqrt(3.0)
    white = 1.0  # constant radiance 1: the white Lambertian pixel has Y = 1
    errs = {s: lod._de(white, render(81), render(s), 95.0) for s in lod.SAMPLE_COUNTS}
    expected = min(s for s in lod.SAMPLE_COUNTS if errs[s] <= share)
    assert choice.anisotropic_samples == expected
    assert expected > 1


def test_unreachable_tolerance_is_reported(metallic: FaceFlopTravelGloss, pixels: Pixels) -> None:
    choice = lod.choose_lod(
        [metallic], sky(), *pixels, tolerance_de=1e-4, samples=32, quadrature_width=64, lobe_counts=[1, 2, 3]
    )
    assert not choice.met
    assert "MISSES" in choice.describe() and choice.notes


def test_input_errors(metallic: FaceFlopTravelGloss, pixels: Pixels) -> None:
    for bad in (0.0, -1.0, float("nan")):
        with pytest.raises(InputError):
            lod.choose_lod([metallic], np.ones((8, 16, 3)), *pixels, tolerance_de=bad)
    with pytest.raises(InputError):
        lod.choose_lod([], np.ones((8, 16, 3)), *pixels)
    with pytest.raises(InputError):
        lod.choose_lod([metallic], np.ones((8, 16, 3)), *pixels, percentile=0.0)


def test_choose_anisotropic_samples_is_the_fewest_within_the_share() -> None:
    """The choice against an independent sweep: the chosen count's ΔE00 (p95, against 81 samples, Lab
    relative to the white Lambertian pixel) is within tolerance/√3 and the next fewer count's is not."""
    from station.model.colorimetry import linear_srgb_to_lab
    from station.model.difference import delta_e
    from station.render import anisotropy as an
    from station.render import prefilter, procedural
    from station.render.cubemap import sample_cube

    basis = prefilter.prefilter_basis(procedural.light_booth(64), (4.0, 64.0, 1024.0, 4096.0), engine="numpy")
    n, v = tr.sphere_pixels(8)
    lobe = an.WardLobe((0.8, 0.8, 0.8), 0.03, 0.3)
    white = float(np.max(sample_cube(basis.diffuse, n)[:, 1]))
    best = an.shade_anisotropic(basis, lobe, 81, n, v)
    err = {
        s: float(
            np.percentile(
                delta_e(
                    linear_srgb_to_lab(best / white),
                    linear_srgb_to_lab(an.shade_anisotropic(basis, lobe, s, n, v) / white),
                    "cie2000",
                ),
                95,
            )
        )
        for s in lod.SAMPLE_COUNTS
    }
    chosen = {}
    for tol in (3.0, 1.0, 0.3):
        c = lod.choose_anisotropic_samples(basis, lobe, n, v, tol)
        share = tol / np.sqrt(3.0)
        i = lod.SAMPLE_COUNTS.index(c.samples)
        assert err[c.samples] <= share or c.samples == 81
        assert i == 0 or err[lod.SAMPLE_COUNTS[i - 1]] > share
        assert c.error_de == pytest.approx(err[c.samples] if c.samples < 81 else 0.0, abs=1e-9)
        chosen[tol] = c.samples
    assert 1 < chosen[3.0] <= chosen[1.0] <= chosen[0.3]
    iso = lod.choose_anisotropic_samples(basis, an.WardLobe((0.8,) * 3, 0.1, 0.1), n, v, 0.3)
    assert iso.samples == 1 and "isotropic" in iso.reason
    with pytest.raises(InputError):
        lod.choose_anisotropic_samples(basis, lobe, n, v, 0.0)


def test_frame_probe_shares_one_widths_coat_map_among_its_bases(metallic) -> None:
    """Without a disk cache a frame probe sums the clear coat's diffuse map once per environment width:
    the bases of one width (other lobe counts) hold the same map, another width its own, and the shared
    map is the one a basis of its own sums."""
    from station.model.gloss import ClearCoat
    from station.render.environment import Environment
    from station.render.prefilter import coat_diffuse_map, prefilter_basis
    from station.render.scene_image import FrameOptions, FrameProbe
    from station.render.shapes import Scene

    env = Environment("sky", sky(32))
    coat = ClearCoat()
    with FrameProbe([metallic], env, Scene("sphere"), FrameOptions(coat=coat, max_size=8)) as probe:
        one, _ = probe.setup(lod.FrameSetting(1, 32))
        two, _ = probe.setup(lod.FrameSetting(2, 32))
        full, _ = probe.setup(lod.FrameSetting(1, None))
        shared = coat_diffuse_map(one, coat)
        assert coat_diffuse_map(two, coat) is shared and coat.index in two.coat_maps
        assert coat.index not in full.coat_maps
    alone = prefilter_basis(env.downsampled(32), two.exponents, engine="numpy", max_size=8)
    assert np.array_equal(coat_diffuse_map(alone, coat), shared)


@pytest.mark.parametrize("errors", ["zero", "rising"])
def test_frame_choice_below_the_margin_draws_only_the_reference_and_the_default(errors: str) -> None:
    """choose_frame_lod with a probe whose error per setting is known: below the margin (tolerance <
    FRAME_MARGIN_DE) only the reference and the default are drawn, and the choice, its estimates and its
    verdict are those of a search over every candidate (a margin of 0 shows what that search draws and
    finds); at or above the margin the search draws candidates, cheapest first, until one fits."""
    candidates = lod.frame_candidates(512)
    ref = np.full((4, 4, 3), 0.5)
    # setting k (0: the reference, 1: the default, then the candidates) draws ref lightened by step * k
    step = 0.0 if errors == "zero" else 0.002
    order = {
        s: k for k, s in enumerate([lod.FrameSetting(lod.MAX_LOBES, None), lod.DEFAULT_SETTING, *candidates])
    }
    drawn: list[lod.FrameSetting] = []

    def probe(s: lod.FrameSetting) -> np.ndarray:
        drawn.append(s)
        return ref * (1.0 + step * order[s])

    margin = lod.FRAME_MARGIN_DE
    below = lod.choose_frame_lod(probe, 1.0, margin - 0.25, candidates)
    assert drawn == [lod.FrameSetting(lod.MAX_LOBES, None), lod.DEFAULT_SETTING]
    assert below.setting == lod.DEFAULT_SETTING and not below.met and "No setting reaches" in below.describe()
    drawn.clear()
    full = lod.choose_frame_lod(probe, 1.0, margin - 0.25, candidates, margin_de=0.0)
    assert len(drawn) > 2  # without the margin the candidates are drawn
    assert below.default_estimate_de == full.default_estimate_de
    if errors == "rising":  # each candidate is further from the reference than the default: none fits
        assert full.setting == lod.DEFAULT_SETTING and len(drawn) == 2 + sum(
            c != lod.DEFAULT_SETTING for c in candidates
        )
    drawn.clear()
    at = lod.choose_frame_lod(probe, 1.0, margin + 0.25, candidates)
    assert len(drawn) >= 3 and drawn[2] == candidates[0]
    assert at.met == (at.estimate_de + margin <= margin + 0.25)
