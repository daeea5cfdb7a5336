"""Appearance under booth illuminants: Lab against colour-science, CAT16 display, metameric pairs, SPD files."""

from __future__ import annotations

import warnings
from pathlib import Path

import colour
import numpy as np
import pytest

from station.errors import InputError
from station.model.booth import (
    fit_under_illuminant,
    lab_to_display_under,
    lab_to_linear_srgb_under,
    light_colour,
    metameric_black,
    metameric_pair,
)
from station.model.fit import fit_fftg
from station.model.illuminants import (
    BOOTH_ILLUMINANTS,
    ILLUMINANT_ALIASES,
    Illuminant,
    SpdFileError,
    booth_illuminant,
    observer_cie_name,
    read_spd_file,
)
from station.model.representations import AspecularMeasurements
from station.model.spectra import (
    WAVELENGTHS,
    metamerism_index,
    reflectance_from_lab,
    reflectance_to_lab,
    weighting_factors,
)

_SHAPE = colour.SpectralShape(400, 700, 10)
#: A blue metallic per geometry (15°, 45°, 110°), Lab D65 / 10°.
_BLUE = np.array([[62.0, 6.0, -34.0], [38.0, 4.0, -28.0], [22.0, 3.0, -20.0]])


def _colour_lab(
    reflectance: np.ndarray, sd_illuminant: colour.SpectralDistribution, observer: str
) -> np.ndarray:
    """colour-science's own Lab: sd_to_XYZ (ASTM E308, same range), white from the same integration."""
    cmfs = colour.MSDS_CMFS[observer]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        white = colour.sd_to_XYZ(
            colour.SpectralDistribution(dict(zip(WAVELENGTHS, np.ones(31), strict=True))),
            cmfs,
            sd_illuminant,
            method="ASTM E308",
            shape=_SHAPE,
        )
        xyz = np.array(
            [
                colour.sd_to_XYZ(
                    colour.SpectralDistribution(dict(zip(WAVELENGTHS, row, strict=True))),
                    cmfs,
                    sd_illuminant,
                    method="ASTM E308",
                    shape=_SHAPE,
                )
                for row in np.atleast_2d(reflectance)
            ]
        )
    return np.asarray(colour.XYZ_to_Lab(xyz / white[1], colour.XYZ_to_xy(white)))


@pytest.fixture(scope="module")
def blue() -> np.ndarray:
    return reflectance_from_lab(_BLUE)


@pytest.mark.parametrize("observer", ["2", "10"])
@pytest.mark.parametrize("name", BOOTH_ILLUMINANTS)
def test_lab_under_each_illuminant_is_colour_science(name: str, observer: str, blue: np.ndarray) -> None:
    full = observer_cie_name(observer)
    sd = colour.SDS_ILLUMINANTS[ILLUMINANT_ALIASES.get(name, name)]
    assert reflectance_to_lab(blue, name, observer) == pytest.approx(_colour_lab(blue, sd, full), abs=1e-6)
    assert reflectance_to_lab(blue, name, full) == pytest.approx(_colour_lab(blue, sd, full), abs=1e-6)


def test_illuminant_own_white_and_aliases(blue: np.ndarray) -> None:
    for name in BOOTH_ILLUMINANTS:
        assert reflectance_to_lab(np.ones(31), name, "2") == pytest.approx([100, 0, 0], abs=1e-9)
    assert np.array_equal(weighting_factors("TL84"), weighting_factors("F11"))
    assert np.array_equal(weighting_factors("tl84"), weighting_factors("FL11"))
    assert booth_illuminant("led-b3").name == "LED-B3"
    # A is not D65: a blue reads very differently under tungsten
    assert np.abs(reflectance_to_lab(blue, "A") - reflectance_to_lab(blue, "D65")).max() > 5


def test_unknown_illuminant_and_observer_are_refused() -> None:
    with pytest.raises(InputError, match="illuminant"):
        weighting_factors("D93")
    with pytest.raises(InputError, match="observer"):
        weighting_factors("D65", "4")


def test_user_spd_file_equals_colour_science(tmp_path: Path, blue: np.ndarray) -> None:
    rows = [(w, 60.0 + 40.0 * np.sin(w / 37.0) ** 2) for w in range(380, 781, 20)]
    path = tmp_path / "lamp.csv"
    path.write_text("# booth lamp\nwavelength_nm,value\n" + "".join(f"{w},{v}\n" for w, v in rows))
    ill = read_spd_file(path)
    assert ill.name == "lamp" and ill.wavelengths_nm[0] == 380.0 and len(ill.values) == len(rows)
    sd = colour.SpectralDistribution(dict(rows), interpolator=colour.LinearInterpolator)
    for obs in ("2", "10"):
        expected = _colour_lab(blue, sd, observer_cie_name(obs))
        assert reflectance_to_lab(blue, ill, obs) == pytest.approx(expected, abs=1e-6)
    # an Illuminant built from a catalogue SPD gives the catalogue's Lab
    assert reflectance_to_lab(blue, booth_illuminant("A")) == pytest.approx(
        reflectance_to_lab(blue, "A"), abs=1e-12
    )


@pytest.mark.parametrize(
    ("text", "field"),
    [
        ("450,1\n500,2\n700,3\n", "wavelength_nm"),  # starts after 400 nm
        ("380,1\n500,2\n690,3\n", "wavelength_nm"),  # ends before 700 nm
        ("380,1\n500,-2\n780,3\n", "row 2: value"),  # negative power
        ("380,1\n500,0\n780,3\n", "row 2: value"),  # zero power
        ("380,1\n380,2\n780,3\n", "row 2: wavelength_nm"),  # not increasing
        ("380,1\n500,abc\n780,3\n", "row 2"),  # not a number
        ("380,1,2\n780,3\n", "row 1"),  # three cells
        ("", "wavelength_nm"),  # empty
    ],
)
def test_bad_spd_file_names_file_and_field(tmp_path: Path, text: str, field: str) -> None:
    path = tmp_path / "bad_lamp.csv"
    path.write_text(text)
    with pytest.raises(SpdFileError) as err:
        read_spd_file(path)
    assert "bad_lamp.csv" in str(err.value) and field in str(err.value)
    assert isinstance(err.value, InputError)


def test_missing_spd_file(tmp_path: Path) -> None:
    with pytest.raises(SpdFileError, match=r"missing\.csv: file"):
        read_spd_file(tmp_path / "missing.csv")


def test_metameric_black_is_invisible_under_d65_only() -> None:
    black = metameric_black()
    assert black @ weighting_factors("D65") == pytest.approx(np.zeros(3), abs=1e-14)
    assert np.linalg.norm(black @ weighting_factors("A")) > 1e-3
    assert np.linalg.norm(black) == pytest.approx(1.0)


def test_metameric_pair_equal_under_d65_different_under_a(blue: np.ndarray) -> None:
    standard, sample = metameric_pair(blue)
    assert standard == pytest.approx(blue) and sample.shape == blue.shape
    assert np.all(sample >= 0) and not np.allclose(sample, standard, atol=1e-3)
    d65 = colour.delta_E(reflectance_to_lab(standard), reflectance_to_lab(sample), method="CIE 2000")
    assert np.all(d65 < 1e-9)
    # the independent expectation under A: colour-science's Lab of both spectra, colour-science's ΔE00
    sd_a = colour.SDS_ILLUMINANTS["A"]
    lab_std = _colour_lab(standard, sd_a, observer_cie_name("10"))
    lab_smp = _colour_lab(sample, sd_a, observer_cie_name("10"))
    expected = colour.delta_E(lab_std, lab_smp, method="CIE 2000")
    assert np.all(expected > 0.5)
    mi = metamerism_index(standard, sample, "D65", ("A", "TL84"))
    assert mi["reference"] == pytest.approx(np.zeros(3), abs=1e-9)
    assert mi["A"] == pytest.approx(expected, abs=1e-6)  # no D65 mismatch, so no correction
    assert np.all(mi["TL84"] > 0)


def test_metamerism_index_additive_correction(blue: np.ndarray) -> None:
    """A sample off under D65 too: the index is the A difference after subtracting the D65 offset."""
    sample = np.clip(blue * 1.05 + np.linspace(0.0, 0.03, 31), 0, 1)
    mi = metamerism_index(blue, sample, "D65", ("A",), observer="2")
    d65 = reflectance_to_lab(sample, "D65", "2") - reflectance_to_lab(blue, "D65", "2")
    corrected = reflectance_to_lab(sample, "A", "2") - d65
    expected = colour.delta_E(reflectance_to_lab(blue, "A", "2"), corrected, method="CIE 2000")
    assert mi["A"] == pytest.approx(expected, abs=1e-9)
    assert np.all(mi["reference"] > 0.1)


def test_fit_under_illuminant_is_the_fit_of_that_lab(blue: np.ndarray) -> None:
    result = fit_under_illuminant(blue, (15, 45, 110), "A", "2")
    lab_a = reflectance_to_lab(blue, "A", "2")
    direct = fit_fftg(AspecularMeasurements((15.0, 45.0, 110.0), lab_a))
    assert result.design == direct.design
    assert result.design.face[0] == pytest.approx(lab_a[0, 0], abs=1e-6)  # L exact through 3 angles
    assert result.design != fit_under_illuminant(blue, (15, 45, 110), "D65").design


def test_display_under_illuminant_is_cat16_to_d65(blue: np.ndarray) -> None:
    from station.model.booth import display_equivalent_lab
    from station.model.colorimetry import lab_to_linear_srgb
    from station.model.display import lab_to_display

    for name in ("A", "F11", "LED-B4"):
        # a perfect white under any illuminant, fully adapted, is the display white
        assert lab_to_linear_srgb_under([100, 0, 0], name) == pytest.approx([1, 1, 1], abs=1e-9)
        lab = reflectance_to_lab(blue, name)
        w = weighting_factors(name).sum(axis=0)
        w65 = weighting_factors("D65").sum(axis=0)
        xyz = colour.Lab_to_XYZ(lab, colour.XYZ_to_xy(w)) * w[1]
        adapted = colour.chromatic_adaptation(xyz, w, w65, method="Von Kries", transform="CAT16")
        expected_lab = colour.XYZ_to_Lab(adapted / w65[1], colour.XYZ_to_xy(w65))
        assert display_equivalent_lab(lab, name) == pytest.approx(expected_lab, abs=1e-9)
        assert lab_to_linear_srgb_under(lab, name) == pytest.approx(
            lab_to_linear_srgb(expected_lab), abs=1e-9
        )
        assert lab_to_display_under(lab, name) == pytest.approx(lab_to_display(expected_lab), abs=1e-9)
        # partial adaptation: Zhai 2018 with D = 1 is the full adaptation
        assert display_equivalent_lab(lab, name, adaptation=1 - 1e-12) == pytest.approx(
            expected_lab, abs=1e-4
        )
    # under D65 the booth changes nothing
    lab = reflectance_to_lab(blue)
    assert display_equivalent_lab(lab, "D65") == pytest.approx(lab, abs=1e-9)
    white_a = lab_to_linear_srgb_under([100, 0, 0], "A", adaptation=0.0)
    assert white_a[0] > white_a[2] * 1.5  # tungsten stays orange to an unadapted eye
    with pytest.raises(InputError, match="adaptation"):
        lab_to_linear_srgb_under([50, 0, 0], "A", adaptation=1.5)


def test_light_colour() -> None:
    a = light_colour("A")
    assert a.max() == pytest.approx(1.0) and a[0] == 1.0 and a[2] < 0.3
    assert light_colour("D65") == pytest.approx([1, 1, 1], abs=1e-9)


def test_metameric_pair_refuses_bad_strength(blue: np.ndarray) -> None:
    for bad in (0.0, 1.5):
        with pytest.raises(InputError, match="strength"):
            metameric_pair(blue, strength=bad)


def test_illuminant_is_hashable_key() -> None:
    a = Illuminant("x", (400.0, 700.0), (1.0, 1.0))
    b = Illuminant("x", (400.0, 700.0), (1.0, 1.0))
    assert hash(a) == hash(b) and weighting_factors(a) is weighting_factors(b)


def test_user_illuminant_from_arrays(blue: np.ndarray) -> None:
    from station.model.illuminants import illuminant_from_spd

    wl = [380.0, 500.0, 780.0]
    lamp = illuminant_from_spd("bench", wl, [1.0, 2.0, 1.5], "body.lamp")
    assert lamp == Illuminant("bench", tuple(wl), (1.0, 2.0, 1.5))
    sd = colour.SpectralDistribution(
        dict(zip(wl, [1.0, 2.0, 1.5], strict=True)), interpolator=colour.LinearInterpolator
    )
    assert reflectance_to_lab(blue, lamp) == pytest.approx(
        _colour_lab(blue, sd, observer_cie_name("10")), abs=1e-6
    )
    for args, field in [
        (("", wl, [1.0, 2.0, 1.5]), "body.lamp.name"),
        (("TL84", wl, [1.0, 2.0, 1.5]), "body.lamp.name"),
        (("x", wl, [1.0, 2.0]), "body.lamp.values"),
        (("x", wl, [1.0, -2.0, 1.5]), "body.lamp.values[1]"),
        (("x", [380.0, 380.0, 780.0], [1.0, 2.0, 1.5]), "body.lamp.wavelengths_nm[1]"),
        (("x", [420.0, 500.0, 780.0], [1.0, 2.0, 1.5]), "body.lamp.wavelengths_nm"),
    ]:
        with pytest.raises(InputError) as err:
            illuminant_from_spd(*args, field="body.lamp")
        assert err.value.field == field


def test_display_equivalent_lab_and_design(blue: np.ndarray) -> None:
    from station.model.booth import display_design_under, display_equivalent_lab
    from station.model.colorimetry import lab_to_linear_srgb

    for name in ("A", "F11", "LED-B3"):
        lab = reflectance_to_lab(blue, name)
        shown = display_equivalent_lab(lab, name)
        assert lab_to_linear_srgb(shown) == pytest.approx(lab_to_linear_srgb_under(lab, name), abs=1e-9)
        result = display_design_under(blue, (15, 45, 110), name, gloss_gu=80.0)
        direct = fit_fftg(AspecularMeasurements((15.0, 45.0, 110.0), shown, 80.0))
        assert result.design == direct.design and result.design.gloss_gu == 80.0
    lab = reflectance_to_lab(blue)
    # under A a fully adapted observer sees the blue still blue, but not the D65 colour
    shown_a = display_equivalent_lab(reflectance_to_lab(blue, "A"), "A")
    assert np.all(shown_a[:, 2] < -15) and np.abs(shown_a - lab).max() > 1
