"""Library browser: type check boxes and the hierarchy filter the list, ColorSnap finds the brute-force
nearest paint, and a match becomes the design (undoably)."""

from __future__ import annotations

import numpy as np
import pytest

from station.formulate.library import Library
from ui.models.document import DesignDocument
from ui.models.library import LibraryModel
from ui.widgets.library_screen import LibraryScreen

pytestmark = [pytest.mark.qt]


def _library(n: int = 60) -> Library:
    rng = np.random.default_rng(7)
    L45 = rng.uniform(25, 75, n)
    a, b = rng.uniform(-50, 50, n), rng.uniform(-50, 50, n)
    lab = np.stack(
        [
            np.stack([L45 + 12, a * 1.1, b * 1.1], -1),
            np.stack([L45, a, b], -1),
            np.stack([L45 - 15, a * 0.8, b * 0.8], -1),
        ],
        axis=1,
    )
    types = np.array(["solid", "metallic", "pearl"])[np.arange(n) % 3]
    return Library(
        "test",
        np.array([f"P{i:03d}" for i in range(n)]),
        types,
        rng.uniform(20, 95, n),
        (15.0, 45.0, 110.0),
        lab,
    )


def test_filters_and_colorsnap(qtbot):
    lib = _library()
    doc = DesignDocument()
    screen = LibraryScreen(LibraryModel(lib), doc)
    qtbot.addWidget(screen)
    screen.resize(1000, 700)
    screen.show()
    assert screen.thumbs.count() == 60
    screen.type_boxes["pearl"].setChecked(False)
    assert screen.thumbs.count() == 40 and "40 paints" in screen.count.text()
    # hierarchy: click the "solids" node → only solids (and not pearls) remain
    solids = screen.tree.topLevelItem(0).child(
        [
            screen.tree.topLevelItem(0).child(i).text(0)
            for i in range(screen.tree.topLevelItem(0).childCount())
        ].index("solids")
    )
    screen._on_tree(solids, 0)
    assert screen.thumbs.count() == int(np.sum(lib.types == "solid")) == int(solids.text(1))

    screen.snap_btn.click()
    design_lab = doc.design.lab_at(np.array([15.0, 45.0, 110.0]))
    brute = np.linalg.norm(lib.lab - design_lab[None], axis=-1).sum(axis=1)  # ΣΔE*ab over the 3 angles
    assert screen.model.snap_result.matches[0].code == lib.codes[np.argmin(brute)]
    assert screen.model.snap_result.matches[0].sum_de == pytest.approx(brute.min(), rel=1e-9)
    assert screen.matches.count() == 5 and screen.cloud.data is not None
    assert screen.compare_model.designs[0] == doc.design
    screen.use_btn.click()
    best = int(np.argmin(brute))
    got = doc.design.lab_at(np.array([15.0, 45.0, 110.0]))
    # the match design is the model's FFTG fit of the paint: its misses are the fit's reported residuals
    from station.model import AspecularMeasurements, fit_fftg

    fit = fit_fftg(AspecularMeasurements((15.0, 45.0, 110.0), lib.lab[best], float(lib.gloss_gu[best])))
    np.testing.assert_allclose(np.linalg.norm(got - lib.lab[best], axis=-1), fit.residual_de, atol=1e-6)
    assert max(fit.residual_de) < 2.0
    doc.undo()
    assert not doc.can_undo
    screen.close()
