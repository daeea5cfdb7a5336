"""The Formulation tab driven by clicks on the 6000-paint demo library: the ColorSnap list keeps its
five matches after Formulate, the recipe shows in the side-by-side table, the closed loop lists the
measured ΔE00 and the tinting additions (colorant, grams for the screen's batch) per step in one clear
sentence's outcome, and the CxF export carries the recipe and the predicted spectra. Every number is
checked against the core calls made here (``station snap`` / ``formulate`` / ``export --recipe``)."""

from __future__ import annotations

import numpy as np
import pytest
from PySide6.QtCore import Qt
from PySide6.QtTest import QTest

from station.formulate.batch import batch_masses
from station.formulate.colorants import predict_lab, predict_reflectance
from station.formulate.cxf import read_cxf_objects
from station.formulate.de_kernels import cie2000
from station.formulate.demo import demo_library
from station.formulate.formulation import formulate_from_library
from station.formulate.snap import color_snap
from station.model import AspecularMeasurements, FaceFlopTravelGloss, fit_fftg
from station.model.domain import ANGLES_3, ANGLES_3_ALT, METAMERISM_TEST_ILLUMINANTS
from station.model.spectra import metamerism_index, reflectance_from_lab
from tests.ui.screens import item_at
from tests.ui.test_journey_chemist import _click, _toggle, _with_dialog
from ui.models.document import DesignDocument
from ui.widgets.formulation_screen import FormulationScreen

pytestmark = [pytest.mark.qt, pytest.mark.slow]

BATCH_G = 500.0


def _metallic_design(k: int) -> FaceFlopTravelGloss:
    """A design fitted to the demo library's *k*-th metallic at 15/45/110°."""
    lib = demo_library()
    i = int(np.flatnonzero(lib.types == "metallic")[k])
    cols = [lib.angles_deg.index(a) for a in ANGLES_3]
    fit = fit_fftg(AspecularMeasurements(ANGLES_3, lib.lab[i][cols], float(lib.gloss_gu[i])))
    return fit.design.replace(name=f"{lib.codes[i]} as a design")


def _loop_table(screen: FormulationScreen) -> list[tuple[int, str, float, dict[str, str]]]:
    """The closed-loop table read back: (step, action, ΔE00, {colorant: grams text}) per step group."""
    t = screen.loop
    groups: list[tuple[int, str, float, dict[str, str]]] = []
    for r in range(t.rowCount()):
        head = t.item(r, 0)
        if head is not None and head.text():
            groups.append((int(head.text()), item_at(t, r, 1).text(), float(item_at(t, r, 2).text()), {}))
        groups[-1][3][item_at(t, r, 3).text()] = item_at(t, r, 4).text()
    return groups


def _cell(table, row_label: str, col: int = 0) -> str:
    rows = [table.verticalHeaderItem(i).text() for i in range(table.rowCount())]
    return table.item(rows.index(row_label), col).text()


def test_formulation_tab(qtbot, tmp_path):
    lib = demo_library()
    design = _metallic_design(3)
    screen = FormulationScreen(lib, DesignDocument(design))
    qtbot.addWidget(screen)
    screen.resize(1400, 900)
    screen.show()
    for kind in ("solid", "pearl"):
        _toggle(screen.types[kind])
    metallic = lib.subset(lib.types == "metallic")
    lab = design.lab_at(np.array(ANGLES_3))
    expected = [m.code for m in color_snap(metallic, lab, k=5, method="cie2000").matches]

    def listed() -> list[str]:
        return [item_at(screen.matches, i, 0).text() for i in range(screen.matches.rowCount())]

    _click(qtbot, screen, screen.snap_btn)
    assert listed() == expected and len(expected) == 5
    # Formulate keeps the five matches (it starts from the best three of them)
    _click(qtbot, screen, screen.formulate_btn)
    assert listed() == expected
    result, found = formulate_from_library(lab, metallic, gloss_gu=design.gloss_target_gu)
    assert [m.code for m in found.matches] == expected[: len(found.matches)]

    # the ranked recipes side by side: g per kg on the scale's resolution, ΔE00 before and after
    # rounding, MI under A and F11, colorants and cost; ΔE00 and MI recomputed here from each recipe
    t, options = screen.recipes, result.recipes
    assert t.columnCount() == len(options) >= 1
    for j, o in enumerate(options):
        header = t.horizontalHeaderItem(j)
        assert header is not None and header.text() == f"#{o.rank} from {o.start}"
        per_kg = 1000.0 / o.batch_g
        for name, mass_g in o.grams.items():
            shown = float(_cell(t, f"{name} (g/kg)", j))
            assert shown == pytest.approx(mass_g * per_kg, abs=0.051)
            assert shown / o.scale_resolution_g == pytest.approx(
                round(shown / o.scale_resolution_g), abs=1e-6
            )
        assert float(_cell(t, "binder (g/kg)", j)) == pytest.approx(o.binder_g * per_kg, abs=0.051)
        de = cie2000(result.design_lab, predict_lab(o.concentrations, result.angles_deg))
        assert float(_cell(t, "ΔE00 after rounding", j)) == pytest.approx(float(de.mean()), abs=0.006)
        assert _cell(t, "ΔE00 before rounding", j) == f"{o.mean_de_unrounded:.2f}"
        assert int(_cell(t, "colorants", j)) == o.colorants <= 5
        assert _cell(t, "cost per kg", j) == f"{o.cost_per_kg:.2f}"
        mi = metamerism_index(
            reflectance_from_lab(result.design_lab),
            predict_reflectance(o.concentrations, result.angles_deg),
            "D65",
            METAMERISM_TEST_ILLUMINANTS,
        )
        for ill in METAMERISM_TEST_ILLUMINANTS:
            assert float(_cell(t, f"MI {ill}", j)) == pytest.approx(float(np.max(mi[ill])), abs=0.006)

    # the closed loop for a 500 g batch: ΔE00 and the additions per step, by hand from the recipes
    screen.batch.setFocus()
    screen.batch.selectAll()
    QTest.keyClicks(screen.batch, f"{BATCH_G:g}")
    QTest.keyClick(screen.batch, Qt.Key.Key_Return)
    _click(qtbot, screen, screen.loop_btn)
    job = screen.job
    groups = _loop_table(screen)
    assert [g[0] for g in groups] == [s.number for s in job.steps]
    assert [g[2] for g in groups] == pytest.approx([s.mean_de for s in job.steps], abs=0.006)
    assert groups[0][1] == "initial"
    assert job.steps[0].batch_g == BATCH_G  # the loop ran for the screen's batch
    for prev, step, (_n, action, _de, lines) in zip(job.steps[:-1], job.steps[1:], groups[1:], strict=True):
        grams = {k: float(v.removeprefix("+").split()[0]) for k, v in lines.items() if v}
        if action == "remake":  # a fresh batch: the new recipe in grams, never additions
            b = batch_masses(step.recipe, BATCH_G)
            assert not any(v.startswith("+") for v in lines.values())
            assert grams == pytest.approx({**b.colorants_g, "binder": b.binder_g}, abs=0.006)
            continue
        # add-only: the previous batch plus the additions shown is this step's recipe (mass balance)
        assert action == "add" and all(v.startswith("+") for v in lines.values() if v)
        before = batch_masses(prev.recipe, prev.batch_g)
        after = {**before.colorants_g, "binder": before.binder_g}
        for name, g in grams.items():
            after[name] = after.get(name, 0.0) + g
        total = sum(after.values())
        assert total == pytest.approx(step.batch_g, abs=0.05)
        mixed = {k: v / total for k, v in after.items() if k != "binder" and v > 0}
        assert mixed == pytest.approx(step.recipe, abs=1e-4)
    assert any(g[1] == "add" for g in groups), "this design's correction is a tinting addition"
    text = screen.status.text()
    n = job.corrections
    assert "converged: converged" not in text and text.count("converged") == 1
    assert f"after {n} correction{'' if n == 1 else 's'}" in text and text.count("correction") == 1

    # CxF export: the design, its match and the recipe with its grams for the batch and its spectra
    path = tmp_path / "blue.cxf"
    _with_dialog(qtbot, screen.export_btn, path, lambda: screen.exported is not None and screen.idle)
    records, extras = read_cxf_objects(path)
    assert len(records) == len(extras) >= 3 and extras[-1] is not None
    b = batch_masses(result.recipe, BATCH_G)
    got = dict(extras[-1].recipe)
    assert got == pytest.approx({**b.colorants_g, "binder": b.binder_g}, abs=1e-3)
    angles = tuple(sorted(set(ANGLES_3) | set(ANGLES_3_ALT)))
    spectra = dict(extras[-1].spectra)
    assert tuple(sorted(spectra)) == pytest.approx(angles)
    refl = predict_reflectance(result.concentrations, angles)
    for a, r in zip(angles, refl, strict=True):
        assert spectra[min(spectra, key=lambda x: abs(x - a))] == pytest.approx(r, abs=1e-4)


def test_formulation_tab_says_when_the_colorant_limit_refuses_the_design(qtbot):
    """The viewer's demo red needs more than 5 colorants: Formulate's status line ends with the
    N-colorant gamut's sentence, the one the core call made here gives."""
    from station.formulate.gamut import formulate_in_gamut

    lib = demo_library()
    red = FaceFlopTravelGloss((62.0, 48.0, 30.0), (24.0, 38.0, 18.0), 70.0, 88.0, "viewer red")
    screen = FormulationScreen(lib, DesignDocument(red))
    qtbot.addWidget(screen)
    screen.show()
    _click(qtbot, screen, screen.formulate_btn)
    result, _ = formulate_in_gamut(red.lab_at(np.array(ANGLES_3)), lib, gloss_gu=red.gloss_target_gu)
    assert result.gamut is not None and not result.gamut.inside and result.gamut.line_inside
    assert result.gamut.message.startswith("outside the 5-colorant gamut of line ")
    status = screen.status.text()
    assert result.gamut.message in status and "NOT formulable" in status
