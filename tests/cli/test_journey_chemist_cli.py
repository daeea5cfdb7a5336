"""The chemist's day through the command line, every step a real ``station`` subprocess run from a
temporary folder (not the repository), on the full demo library:

a stylist's design file (typed Lab, not drawn by the colorant model) → ``station formulate`` with the
default options → the recipe weighed out as a 1000 g batch at the scale's resolution → the batch sprayed
and the panel read by the MA6 simulator over its pseudo-terminal (``station measure sim:ma6 --recipe``),
stored in an SQLite database → ``station tint`` from the stored reading: add-only additions in grams →
the tinted batch sprayed and read again (a CxF3 file) → its ΔE00 to the design is lower.

The one thing planted is the lab's reality the model does not know: the orange toner in the can is
:data:`STRENGTH` as strong as the colorant database says (a weak toner batch). In Kubelka–Munk a toner
whose K and S are scaled by s is the same paint as s × its mass fraction, so the sprayed panel's recipe
(handed to the simulator) is the can's with the orange fraction scaled by s, for the first batch and for
the tinted one alike (the addition comes out of the same can). Every expected ΔE00 is computed here with
colour-science from the stored readings, and the predicted ΔE00 after the addition from the colorant
model's public :func:`station.formulate.predict_lab`.
"""

from __future__ import annotations

import hashlib
import json
import subprocess
from pathlib import Path
from typing import Any

import colour
import numpy as np
import pytest

from station.formulate import predict_lab
from station.formulate.batch import MAX_GROWTH
from station.ingest.formats import read_measurement_file
from station.model import AspecularMeasurements, fit_fftg
from station.model.design_io import save_design
from station.model.domain import DEFAULT_MAX_COLORANTS, DEFAULT_SCALE_RESOLUTION_G, aspecular_name
from tests.user_cli import run_station

#: The stylist's terracotta solid door colour at 15/45/110° (typed, as a stylist edits a swatch).
DESIGN_LAB = ((55.4, 30.5, 20.3), (55.0, 30.2, 20.0), (54.7, 30.0, 19.8))
ANGLES = (15.0, 45.0, 110.0)
WEAK = "orange_po"
#: Tinting strength of the orange toner in the can against the colorant database's (a weak batch).
STRENGTH = 0.8
BATCH_G = 1000.0


def station(cwd: Path, *args: str) -> subprocess.CompletedProcess[str]:
    res = run_station(cwd, *args, timeout=120)
    assert res.returncode == 0, f"station {' '.join(args)}: {res.stderr}"
    return res


def refused(cwd: Path, *args: str) -> str:
    """Run a command that must be refused: exit 2, one line on stderr, nothing on stdout."""
    res = run_station(cwd, *args, timeout=120)
    lines = res.stderr.strip().splitlines()
    assert res.returncode == 2 and len(lines) == 1 and not res.stdout.strip(), (res.returncode, res.stderr)
    return lines[0]


def _de00(a: Any, b: Any) -> np.ndarray:
    """CIEDE2000 per row (colour-science, k_L = k_C = k_H = 1)."""
    return np.asarray(colour.delta_E(np.asarray(a, float), np.asarray(b, float), method="CIE 2000"), float)


def _sprayed(batch: dict[str, Any], path: Path) -> dict[str, float]:
    """Write the panel actually sprayed from *batch* (grams in the can) as a recipe file for the
    simulator: mass fractions, the weak toner at :data:`STRENGTH`; return that recipe."""
    total = float(batch["total_g"])
    recipe = {n: g / total * (STRENGTH if n == WEAK else 1.0) for n, g in batch["colorants_g"].items()}
    path.write_text(json.dumps({"recipe": recipe}), encoding="utf-8")
    return recipe


def _fractions(batch: dict[str, Any]) -> np.ndarray:
    """The can's mass fractions in the colorant database's order."""
    from station.formulate import default_database

    db = default_database()
    total = float(sum(batch["colorants_g"].values()) + batch["binder_g"])
    return db.vector({n: g / total for n, g in batch["colorants_g"].items()})


def _on_scale(grams: float, step: float = DEFAULT_SCALE_RESOLUTION_G) -> bool:
    return abs(grams / step - round(grams / step)) < 1e-6


def _lab_at(geometries: list[str] | tuple[str, ...], lab: Any) -> np.ndarray:
    """Rows of *lab* at the 45° geometries of :data:`ANGLES`."""
    rows = [list(geometries).index(aspecular_name(a)) for a in ANGLES]
    return np.asarray(lab, float)[rows]


@pytest.fixture
def lab(tmp_path: Path) -> dict[str, Any]:
    work = tmp_path / "lab"
    work.mkdir()
    url = f"sqlite:///{work / 'lab.sqlite3'}"
    station(work, "db", "upgrade", "--database", url)
    fit = fit_fftg(AspecularMeasurements(ANGLES, np.array(DESIGN_LAB), 88.0))
    save_design(fit.design.replace(name="terracotta door"), work / "terracotta.json")
    return {"work": work, "url": url, "db": work / "lab.sqlite3"}


@pytest.mark.slow
def test_the_chemist_weighs_sprays_measures_and_tints(lab: dict[str, Any]) -> None:
    work, url = lab["work"], lab["url"]

    # (1) formulate with the default options: the recipe table and the 1000 g batch in grams
    out = json.loads(station(work, "formulate", "terracotta.json", "--json").stdout)
    (work / "recipe.json").write_text(json.dumps(out), encoding="utf-8")
    assert out["formulable"] and out["line"] == "solid" and out["library"].startswith("demo")
    assert out["matches"] and all(m["code"].startswith("SYN-") for m in out["matches"])  # demo paints
    design = np.array(out["design_lab"])  # the design file at 15/45/110°
    assert np.allclose(design, DESIGN_LAB, atol=0.02)  # as the stylist typed it
    batch = out["batch"]
    assert batch["total_g"] == BATCH_G
    assert sum(batch["colorants_g"].values()) + batch["binder_g"] == pytest.approx(BATCH_G, abs=1e-6)
    assert all(_on_scale(g) for g in [*batch["colorants_g"].values(), batch["binder_g"]])
    counted = [n for n in batch["colorants_g"] if n != "matting_silica"]
    assert 1 <= len(counted) <= DEFAULT_MAX_COLORANTS and WEAK in counted
    for r in out["recipes"]:  # every recipe of the side-by-side table is weighable
        assert (
            r["colorants"] <= DEFAULT_MAX_COLORANTS and r["scale_resolution_g"] == DEFAULT_SCALE_RESOLUTION_G
        )
        assert all(_on_scale(g) for g in [*r["grams"].values(), r["binder_g"]])
        assert sum(r["grams"].values()) + r["binder_g"] == pytest.approx(r["batch_g"], abs=1e-6)
    assert out["recipes"][0]["grams"] == batch["colorants_g"]

    # (2) spray the batch, read the panel with the MA6 simulator, store the reading
    _sprayed(batch, work / "panel-1.json")
    first = json.loads(
        station(work, "measure", "sim:ma6", "--recipe", "panel-1.json", "--store", url, "--json").stdout
    )
    mid = first["stored"]["measurement_id"]
    measured = _lab_at(first["geometries"], first["lab"])
    de_first = _de00(design, measured)
    assert de_first.mean() > 1.0  # the weak toner shows: out of the tolerance

    # (3) correct by additions, from the stored reading
    tint = json.loads(
        station(work, "tint", "recipe.json", "--db", url, "--measurement", str(mid), "--json").stdout
    )
    _assert_additions(out, tint, measured)

    # (4) spray the tinted batch, read it again (a CxF3 file this time): ΔE00 reduced
    (work / "tinted.json").write_text(json.dumps(tint), encoding="utf-8")
    _sprayed(tint["batch"], work / "panel-2.json")
    station(work, "measure", "sim:ma6", "--recipe", "panel-2.json", "--store", url, "--out", "panel-2.cxf")
    (second,) = read_measurement_file(work / "panel-2.cxf").measurements
    de_second = _de00(design, _lab_at(second.geometries, second.lab))
    assert de_second.mean() < de_first.mean() - 0.3, (de_first, de_second)
    assert de_second.mean() == pytest.approx(tint["predicted_mean_de"], abs=0.3)  # as the model predicted
    again = json.loads(station(work, "tint", "tinted.json", "--measured", "panel-2.cxf", "--json").stdout)
    assert again["measured_mean_de"] == pytest.approx(float(de_second.mean()), abs=1e-6)
    assert again["first_batch_g"] == BATCH_G  # a second correction is bounded by the first batch

    _failures(work, lab["db"], first)


def _assert_additions(out: dict[str, Any], tint: dict[str, Any], measured: np.ndarray) -> None:
    """Add-only grams on the scale, within the batch's bounds; the predicted ΔE00 after the addition
    recomputed with the colorant model's predict_lab and colour-science, lower than the measured one."""
    design = np.array(out["design_lab"])
    before, after = out["batch"], tint["batch"]
    assert not tint["remake"], tint["message"]
    assert tint["measured_mean_de"] == pytest.approx(float(_de00(design, measured).mean()), abs=1e-6)
    adds = tint["additions_g"]
    assert adds and set(adds) <= set(before["colorants_g"])  # the recipe's own colorants only
    assert all(g > 0 and _on_scale(g) for g in adds.values())
    assert tint["binder_added_g"] >= 0 and _on_scale(tint["binder_added_g"])
    for name, grams in before["colorants_g"].items():  # after = before + additions, nothing taken out
        assert after["colorants_g"][name] == pytest.approx(grams + adds.get(name, 0.0), abs=1e-6)
    assert after["binder_g"] == pytest.approx(before["binder_g"] + tint["binder_added_g"], abs=1e-6)
    total = sum(after["colorants_g"].values()) + after["binder_g"]
    assert after["total_g"] == pytest.approx(total, abs=1e-6)
    assert BATCH_G < total <= MAX_GROWTH * BATCH_G
    assert adds.get(WEAK, 0.0) > 0  # the weak toner is topped up
    # independent: target = design − (measured − P(can)), predicted = P(can after the additions)
    target = design - (measured - predict_lab(_fractions(before), ANGLES))
    predicted = predict_lab(_fractions(after), ANGLES)
    expected = float(_de00(target, predicted).mean())
    assert tint["predicted_mean_de"] == pytest.approx(expected, abs=1e-6)
    assert expected < tint["measured_mean_de"] - 0.3


def _failures(work: Path, db: Path, reading: dict[str, Any]) -> None:
    """Bad input: exit 2, one line naming the field, nothing stored changed and no file written. The
    reading of another geometry set is the first panel's (``station measure --json`` output) as a
    five-angle instrument without 45as110 reports it."""
    rec = json.loads((work / "recipe.json").read_text(encoding="utf-8"))
    alien = json.loads(json.dumps(rec))
    alien["batch"]["colorants_g"]["alu_bright"] = 2.0  # a metallic line's aluminium in a solid batch
    alien["batch"]["binder_g"] -= 2.0
    (work / "alien.json").write_text(json.dumps(alien), encoding="utf-8")
    first = json.loads((work / "tinted.json").read_text(encoding="utf-8"))
    mid = reading["stored"]["measurement_id"]
    reading = json.loads(json.dumps(reading))
    keep = [i for i, g in enumerate(reading["geometries"]) if g != "45as110"]  # a 5-angle instrument
    for key in ("geometries", "lab", "spectra"):
        reading[key] = [reading[key][i] for i in keep]
    (work / "five.json").write_text(json.dumps(reading), encoding="utf-8")
    stored = hashlib.sha256(db.read_bytes()).hexdigest()
    files = sorted(p.name for p in work.iterdir())
    stored_db = ("--db", f"sqlite:///{db}", "--measurement", str(mid))
    assert "recipe_file" in refused(work, "tint", "missing.json", *stored_db)
    assert "--measured" in refused(work, "tint", "recipe.json", "--measured", "missing.cxf")
    assert "recipe.alu_bright" in refused(work, "tint", "alien.json", *stored_db)
    line = refused(work, "tint", "recipe.json", "--measured", "five.json")
    assert "measured.geometries" in line and "45as110" in line
    assert "--measurement" in refused(work, "tint", "recipe.json", *stored_db[:3], "999")
    assert first["recipe"]  # the saved correction is untouched by the refusals
    assert hashlib.sha256(db.read_bytes()).hexdigest() == stored
    assert sorted(p.name for p in work.iterdir()) == files
