"""Booth screen with a recipe as the trial: "From recipe…" (a recipe JSON file) and a service's formulation
jobs, driven by clicks on real widgets; the table's trial Lab is the colorant model's prediction."""

from __future__ import annotations

import json

import numpy as np
import pytest
from PySide6.QtCore import Qt
from PySide6.QtWidgets import QFileDialog

from station.formulate.colorants import default_database, predict_reflectance
from station.model.difference import delta_e
from station.model.spectra import reflectance_to_lab
from station.render.booth import BoothRenderer
from tests.ui.test_booth import ANGLES, SIZE, _click, _database, _pick, spectra  # noqa: F401
from ui.models.booth import BoothModel, LocalBoothSource
from ui.widgets.booth_screen import COLUMNS, BoothScreen

pytestmark = [pytest.mark.qt]

#: A red metallic recipe of the built-in (SYNTHETIC) colorants, mass fractions.
RECIPE = {"red_pr": 0.08, "magenta_pv": 0.01, "alu_bright": 0.04, "white_tio2": 0.005}


def _cell(screen: BoothScreen, i: int, column: str) -> str:
    item = screen.table.item(i, COLUMNS.index(column))
    assert item is not None
    return item.text()


def _labs(screen: BoothScreen, column: str) -> np.ndarray:
    n = screen.table.rowCount()
    return np.array([[float(v) for v in _cell(screen, i, column).split(",")] for i in range(n)])


def _predicted(angles: list[float]) -> np.ndarray:
    db = default_database()
    return predict_reflectance(db.vector(RECIPE), tuple(angles), db)


def test_trial_from_a_recipe_file(qtbot, tmp_path, spectra, monkeypatch) -> None:  # noqa: F811
    url, std_id, _ = _database(tmp_path, spectra)
    screen = BoothScreen(BoothModel(LocalBoothSource(url), BoothRenderer(SIZE)))
    qtbot.addWidget(screen)
    screen.show()
    _pick(qtbot, screen, "standard", std_id)
    recipe = tmp_path / "recipe.json"
    recipe.write_text(json.dumps({"design": "red", "recipe": RECIPE, "mean_de": 0.4}))
    monkeypatch.setattr(QFileDialog, "getOpenFileName", lambda *a, **k: (str(recipe), ""))
    assert screen.recipe_btn.text() == "From recipe…"
    _click(qtbot, screen.recipe_btn)
    assert screen.table.rowCount() == len(ANGLES), screen.message.text()
    predicted = _predicted(ANGLES)  # at the standard's five geometries
    for name in ("D65", "A"):
        if name != "D65":
            _click(qtbot, screen.illuminant_btns[name])
        np.testing.assert_allclose(
            _labs(screen, "trial L*a*b*"), reflectance_to_lab(predicted, name), atol=0.006
        )
        de = delta_e(reflectance_to_lab(spectra[0], name), reflectance_to_lab(predicted, name), "cie2000")
        np.testing.assert_allclose(
            np.array([float(_cell(screen, i, "ΔE00")) for i in range(len(ANGLES))]), de, atol=0.006
        )
    assert "recipe recipe.json" in screen.message.text()
    # a measurement file is not a recipe: a visible message naming it
    (tmp_path / "notes.json").write_text('{"colour": "red"}')
    monkeypatch.setattr(QFileDialog, "getOpenFileName", lambda *a, **k: (str(tmp_path / "notes.json"), ""))
    _click(qtbot, screen.recipe_btn)
    assert "error" in screen.message.text() and "notes.json" in screen.message.text()


def test_trial_from_a_services_formulation_job(qtbot, tmp_path, spectra) -> None:  # noqa: F811
    from sqlalchemy import select

    from db.models import DesignVersion, FormulationJob
    from tests.api.conftest import make_api
    from tests.ingest._readings import make_reading
    from ui.models.booth import ServiceBoothSource
    from ui.models.service import ServiceClient

    angles = [15.0, 45.0, 110.0]
    rows = [ANGLES.index(a) for a in angles]
    gen = make_api(f"sqlite:///{tmp_path / 'station.sqlite3'}", tmp_path)
    api = next(gen)
    try:
        tech = api.auth("technician")
        body = make_reading(7, 0).model_dump(mode="json")
        body["lab"] = reflectance_to_lab(spectra[0][rows]).round(4).tolist()
        body["spectra"] = spectra[0][rows].tolist()
        r = api.client.post("/api/v1/measurements", json=body, headers=tech)
        assert r.status_code == 201, r.text
        std_id = r.json()["id"]
        design = {"name": "red", "face": [48.0, 42.0, 22.0], "flop": [18.0, 24.0, 10.0], "travel_deg": 60.0}
        d = api.client.post(
            "/api/v1/designs", json={"name": "red", "design": design}, headers=api.auth("stylist")
        )
        assert d.status_code == 201, d.text
        with api.client.app.state.sessions() as session:  # type: ignore[attr-defined]
            dv = session.scalars(select(DesignVersion).where(DesignVersion.design_id == d.json()["id"])).one()
            jobs = [
                FormulationJob(
                    design_version_id=dv.id, state=state, target={}, recipe={"candidates": [], "recipe": rc}
                )
                for state, rc in (("failed", None), ("done", RECIPE))
            ]
            session.add_all(jobs)
            session.commit()
            empty_id, job_id = (j.id for j in jobs)
        service = ServiceClient("http://testserver", api.tokens[next(iter(api.tokens))], client=api.http)
        s = BoothScreen(BoothModel(ServiceBoothSource(service), BoothRenderer(SIZE)))
        qtbot.addWidget(s)
        s.show()
        assert s.recipe_jobs.isVisible()
        _pick(qtbot, s, "standard", std_id)

        def choose(rid: int) -> None:
            index = s.recipe_jobs.findData(rid)
            assert index > 0, [s.recipe_jobs.itemText(i) for i in range(s.recipe_jobs.count())]
            s.recipe_jobs.setFocus()
            _click(qtbot, s.recipe_jobs)
            view = s.recipe_jobs.view()
            view.setCurrentIndex(s.recipe_jobs.model().index(index, 0))
            qtbot.keyClick(view, Qt.Key.Key_Return)

        choose(empty_id)
        assert "error" in s.message.text() and f"recipe {empty_id}" in s.message.text()
        choose(job_id)
        _click(qtbot, s.illuminant_btns["F11"])
        assert s.table.rowCount() == len(angles), s.message.text()
        np.testing.assert_allclose(
            _labs(s, "trial L*a*b*"), reflectance_to_lab(_predicted(angles), "F11"), atol=0.006
        )
        assert f"recipe #{job_id}" in s.message.text()
    finally:
        gen.close()
