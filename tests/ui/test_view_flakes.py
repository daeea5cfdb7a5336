"""The flake parameters in the viewer: size, density and spread boxes driven by QTest write the view's
settings, and the layer drawn is the paint type's default with them put in."""

from __future__ import annotations

from typing import Any

import pytest
from PySide6.QtCore import Qt
from PySide6.QtTest import QTest

from station.model import FaceFlopTravelGloss
from station.model.flakes import METALLIC_FLAKES, PEARL_FLAKES, FlakeLayer
from ui.models.view import ViewInputError, ViewModel, ViewSettings
from ui.widgets.render_view import GLRenderView
from ui.widgets.view_panel import ViewPanel

pytestmark = [pytest.mark.qt]

SILVER = FaceFlopTravelGloss((90.0, 0.0, 0.0), (30.0, 0.0, 0.0), 60.0, 88.0)
PEARL = FaceFlopTravelGloss((70.0, -22.0, -18.0), (38.0, 14.0, -34.0), 70.0, 86.0)


def test_settings_put_the_parameters_into_the_paint_default() -> None:
    s = ViewSettings(flakes=True, flake_size_um=40.0, flake_spread_deg=4.0)
    assert s.flake_layer(SILVER) == FlakeLayer(40.0, METALLIC_FLAKES.density_per_mm2, 4.0, 0.5)
    pearl = s.flake_layer(PEARL)
    assert pearl is not None and pearl.density_per_mm2 == PEARL_FLAKES.density_per_mm2
    assert pearl.reflectance == PEARL_FLAKES.reflectance and pearl.size_um == 40.0
    assert ViewSettings(flake_size_um=40.0).flake_layer(SILVER) is None  # flakes off
    for name, bad in (("flake_size_um", 0.0), ("flake_density", 1e6), ("flake_spread_deg", 60.0)):
        with pytest.raises(ViewInputError, match=name):
            bad_field: dict[str, Any] = {name: bad}
            ViewSettings(**bad_field)


def test_flake_boxes_drive_the_layer(qtbot, tmp_path, monkeypatch) -> None:
    monkeypatch.setenv("CACAD_CACHE_DIR", str(tmp_path / "cache"))
    model = ViewModel(ViewSettings(flakes=True))
    model.show(SILVER)
    panel = ViewPanel(model)
    qtbot.addWidget(panel)
    panel.show()
    qtbot.waitExposed(panel)
    size = panel.flake_boxes["flake_size_um"]
    assert size.text() == "size: paint default" and model.settings.flake_size_um is None
    size.setFocus()
    size.selectAll()
    QTest.keyClicks(size, "60")
    QTest.keyClick(size, Qt.Key.Key_Enter)
    assert model.settings.flake_size_um == 60.0
    spread = panel.flake_boxes["flake_spread_deg"]
    spread.setFocus()
    QTest.keyClick(spread, Qt.Key.Key_Up)  # from "paint default" one step up: the range's lowest, 0.5°
    assert model.settings.flake_spread_deg == 0.5
    assert isinstance(panel.view, GLRenderView)
    layer = panel.view._flake_layer()
    assert layer == FlakeLayer(60.0, METALLIC_FLAKES.density_per_mm2, 0.5, METALLIC_FLAKES.reflectance)
    QTest.keyClick(spread, Qt.Key.Key_Down)  # back to the paint default
    assert model.settings.flake_spread_deg is None
    panel.close()
