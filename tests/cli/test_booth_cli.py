"""``station booth`` from a user's folder: a constructed metameric pair written to import files, read back."""

from __future__ import annotations

import json
from pathlib import Path

import colour
import numpy as np
import pytest

from station.ingest.errors import ImportFileError
from station.ingest.formats import write_measurement_file
from station.ingest.formats.measurement import ImportedMeasurement, Instrument, build_measurement
from station.model.booth import metameric_pair
from station.model.colorimetry import OBSERVER_10
from station.model.spectra import WAVELENGTHS, reflectance_from_lab
from tests.user_cli import run_station

GEOMETRIES = ("45as15", "45as45", "45as110")
#: A red metallic per geometry, Lab D65 / 10°.
RED = [[48.0, 42.0, 22.0], [30.0, 34.0, 16.0], [18.0, 24.0, 10.0]]


def _measurement(name: str, spectra: np.ndarray, lab: bool = False) -> ImportedMeasurement:
    def err(f: str, a: str, g: object) -> ImportFileError:
        return ImportFileError("test", name, f, a, g)

    return build_measurement(
        sample=name,
        rows=[(g, err) for g in GEOMETRIES],
        lab=RED if lab else None,
        wavelengths_nm=None if lab else WAVELENGTHS.tolist(),
        spectra=None if lab else spectra.round(6).tolist(),
        instrument=Instrument(model="MA-T12", serial="T1"),
        illuminant="D65",
        observer=OBSERVER_10,
        measured_at=None,
        err=err,
    )


def _lab(refl: np.ndarray, illuminant: str) -> np.ndarray:
    cmfs = colour.MSDS_CMFS[OBSERVER_10]
    ill = colour.SDS_ILLUMINANTS[{"F11": "FL11"}.get(illuminant, illuminant)]
    rows = []
    for r in refl:
        sd = colour.SpectralDistribution(dict(zip(WAVELENGTHS, r, strict=True)))
        xyz = colour.sd_to_XYZ(sd, cmfs, ill, method="ASTM E308") / 100
        white = colour.sd_to_XYZ(colour.sd_ones(sd.shape), cmfs, ill, method="ASTM E308") / 100
        rows.append(colour.XYZ_to_Lab(xyz, colour.XYZ_to_xy(white)))
    return np.asarray(rows)


@pytest.fixture(scope="module")
def pair() -> tuple[np.ndarray, np.ndarray]:
    std, smp = metameric_pair(reflectance_from_lab(RED), strength=0.4)
    return std.round(6), smp.round(6)


@pytest.mark.parametrize("suffix", [".cxf", ".csv"])
def test_booth_reads_a_metameric_pair_back(
    tmp_path: Path, pair: tuple[np.ndarray, np.ndarray], suffix: str
) -> None:
    std, smp = pair
    write_measurement_file([_measurement("standard", std)], tmp_path / f"standard{suffix}")
    write_measurement_file([_measurement("trial", smp)], tmp_path / f"trial{suffix}")
    out = run_station(
        tmp_path, "booth", "--standard", f"standard{suffix}", "--sample", f"trial{suffix}",
        "--illuminants", "D65,A,F11", "--observer", "10", "--shape", "car", "--json",
    )  # fmt: skip
    assert out.returncode == 0, out.stderr
    doc = json.loads(out.stdout)
    assert set(doc) == {"illuminants", "reference"} and doc["reference"] == "D65"
    by_name = {i["name"]: i for i in doc["illuminants"]}
    assert list(by_name) == ["D65", "A", "F11"]
    assert [g["geometry"] for g in by_name["A"]["per_geometry"]] == list(GEOMETRIES)
    assert all(g["dE00"] < 1e-3 for g in by_name["D65"]["per_geometry"])
    for name in ("A", "F11"):
        expected = colour.delta_E(_lab(std, name), _lab(smp, name), method="CIE 2000")
        got = [g["dE00"] for g in by_name[name]["per_geometry"]]
        assert got == pytest.approx(expected, abs=1e-3)
        assert [g["metamerism_index"] for g in by_name[name]["per_geometry"]] == pytest.approx(
            expected, abs=1e-3
        )
        assert by_name[name]["per_geometry"][0]["standard_lab"] == pytest.approx(_lab(std, name)[0], abs=1e-4)
    assert min(g["dE00"] for g in by_name["A"]["per_geometry"]) > 0.5
    table = run_station(tmp_path, "booth", "--standard", f"standard{suffix}", "--sample", f"trial{suffix}")
    assert table.returncode == 0, table.stderr
    assert "45as110" in table.stdout and "reference illuminant: D65" in table.stdout
    a_row = next(line for line in table.stdout.splitlines() if line.startswith("A ") and "45as15" in line)
    assert f"{by_name['A']['per_geometry'][0]['dE00']:.2f}" in a_row


def test_booth_user_spd_and_2_degree(tmp_path: Path, pair: tuple[np.ndarray, np.ndarray]) -> None:
    std, smp = pair
    write_measurement_file([_measurement("standard", std)], tmp_path / "s.cxf")
    write_measurement_file([_measurement("trial", smp)], tmp_path / "t.cxf")
    (tmp_path / "lamp.csv").write_text(
        "wavelength_nm,value\n" + "".join(f"{w},{100 + w / 10}\n" for w in range(380, 781, 10))
    )
    out = run_station(
        tmp_path, "booth", "--standard", "s.cxf", "--sample", "t.cxf", "--illuminants", "TL84,lamp.csv,LED-B3",
        "--observer", "2", "--json",
    )  # fmt: skip
    assert out.returncode == 0, out.stderr
    assert [i["name"] for i in json.loads(out.stdout)["illuminants"]] == ["TL84", "lamp", "LED-B3"]


def test_booth_refusals(tmp_path: Path, pair: tuple[np.ndarray, np.ndarray]) -> None:
    std, _ = pair
    write_measurement_file([_measurement("standard", std)], tmp_path / "s.cxf")
    write_measurement_file([_measurement("labonly", std, lab=True)], tmp_path / "labonly.cxf")
    (tmp_path / "bad_lamp.csv").write_text("450,1\n700,2\n")
    cases = [
        (["--sample", "labonly.cxf"], "labonly.cxf"),
        (["--sample", "s.cxf", "--illuminants", "D65,D93"], "illuminant"),
        (["--sample", "s.cxf", "--illuminants", "bad_lamp.csv"], "bad_lamp.csv"),
        (["--sample", "s.cxf", "--observer", "4"], "observer"),
        (["--sample", "s.cxf", "--shape", "boat"], "shape"),
    ]
    for extra, named in cases:
        out = run_station(tmp_path, "booth", "--standard", "s.cxf", *extra, "--json")
        assert out.returncode == 2, (extra, out.stderr)
        assert named in out.stderr and len(out.stderr.strip().splitlines()) == 1, out.stderr
        assert out.stdout == ""
