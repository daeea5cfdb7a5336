"""Loading an .hdr/.exr environment in the viewer: the panel's button and file dialog driven by QTest clicks,
the model's ``load_environment`` (for the File menu), and a broken file refused with the view unchanged."""

from __future__ import annotations

import numpy as np
import pytest
from PySide6.QtCore import Qt
from PySide6.QtTest import QTest

from station.render.errors import EnvironmentFileError
from ui.models.document import DEFAULT_DESIGN
from ui.models.view import ViewInputError, ViewModel, ViewSettings
from ui.widgets.view_panel import ViewPanel

pytestmark = [pytest.mark.qt]


@pytest.fixture
def own_cache(tmp_path, monkeypatch):
    monkeypatch.setenv("CACAD_CACHE_DIR", str(tmp_path / "cache"))


def _panel(qtbot, model: ViewModel) -> ViewPanel:
    panel = ViewPanel(model)
    qtbot.addWidget(panel)
    panel.resize(320, 150)
    panel.show()
    qtbot.waitExposed(panel)
    panel.view.wait_idle()
    return panel


def test_model_load_environment_validates(tmp_path) -> None:
    model = ViewModel()
    bad = tmp_path / "broken.hdr"
    bad.write_bytes(b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 2 +X 4\n")  # truncated pixels
    with pytest.raises(EnvironmentFileError):
        model.load_environment(bad)
    with pytest.raises(ViewInputError, match="environment"):
        model.load_environment(tmp_path / "missing.hdr")
    with pytest.raises(ViewInputError, match="environment"):
        ViewSettings(environment=str(tmp_path / "picture.png"))
    assert model.settings.environment == "booth"


def test_model_loads_a_photographed_hdr(hdri_files) -> None:
    from ui.models.view import ENV_WIDTH

    model = ViewModel()
    env = model.load_environment(hdri_files[0])
    assert model.settings.environment == str(hdri_files[0])
    assert env.equirect.shape == (ENV_WIDTH // 2, ENV_WIDTH, 3)  # 1k file at the viewer's width
    assert np.all(np.isfinite(env.equirect)) and env.equirect.max() > 1.0  # HDR, not clipped


@pytest.mark.gl
def test_load_hdr_button_and_dialog(qtbot, hdri_files, own_cache, tmp_path) -> None:
    from station.render.environment import load_environment
    from station.render.hdr_io import write_hdr

    # The photographed environments written small (64 × 32) as real Radiance files: the same path through
    # the reader, and prefilters the test can wait for. The view starts in the first, the dialog loads
    # the last.
    small = []
    for src in (hdri_files[0], hdri_files[-1]):
        small.append(tmp_path / f"{src.stem}_64.hdr")
        write_hdr(small[-1], load_environment(src).downsampled(64).equirect)
    model = ViewModel(ViewSettings(environment=str(small[0])))
    model.show(DEFAULT_DESIGN)
    panel = _panel(qtbot, model)
    qtbot.waitUntil(lambda: panel.view.full_quality, timeout=60000)
    before = panel.view.grab_image().astype(float)
    assert panel.environment.currentText() == small[0].name
    QTest.mouseClick(panel.load_env, Qt.MouseButton.LeftButton)
    qtbot.waitUntil(panel.env_dialog.isVisible, timeout=5000)
    panel.env_dialog.selectFile(str(small[1]))
    panel.env_dialog.accept()  # what a double click on the file does: fileSelected(path)
    assert model.settings.environment == str(small[1])
    assert panel.environment.currentText() == small[1].name
    assert panel.env_status.text() == ""
    panel.view.wait_idle(60000)
    qtbot.waitUntil(lambda: panel.view.full_quality, timeout=60000)
    # the frame shown is the core's picture of this file's prefiltered maps
    assert panel.view.basis.core.basis is panel.view.environment_prefilter(str(small[1]))
    after = panel.view.grab_image()
    np.testing.assert_array_equal(after, panel.view.basis.core.edit(list(model.weights()), 0.0))
    obj = panel.view.basis.paint >= 0
    assert obj.mean() > 0.05
    if hdri_files[0] != hdri_files[-1]:  # a different light: the object's mean colour moves
        assert np.abs(after[obj].astype(float).mean(axis=0) - before[obj].mean(axis=0)).max() > 3
    # picking the first file again from the combo returns to it
    panel.environment.setCurrentIndex(panel.environment.findData(str(small[0])))
    assert model.settings.environment == str(small[0])
    panel.view.wait_idle()
    panel.close()


def test_broken_file_is_refused_and_said(qtbot, tmp_path) -> None:
    bad = tmp_path / "broken.hdr"
    bad.write_bytes(b"not an image")
    model = ViewModel()
    panel = ViewPanel(model)
    qtbot.addWidget(panel)
    QTest.mouseClick(panel.load_env, Qt.MouseButton.LeftButton)
    qtbot.waitUntil(panel.env_dialog.isVisible, timeout=5000)
    panel.env_dialog.selectFile(str(bad))
    panel.env_dialog.accept()
    assert model.settings.environment == "booth"
    assert panel.env_status.text().startswith("not loaded:")
    assert "broken.hdr" in panel.env_status.text()
    assert panel.environment.currentText() == "booth"
    panel.close()


@pytest.mark.gl
def test_stage_checkbox_same_picture_on_both_paths(qtbot, tmp_path, hdri_files, own_cache) -> None:
    """Backdrop + ground: the GL frame of a view change and the cached basis agree (corner and object)."""
    from station.render.environment import load_environment
    from station.render.hdr_io import write_hdr

    path = tmp_path / "small.hdr"
    write_hdr(path, load_environment(hdri_files[0]).downsampled(64).equirect)
    model = ViewModel(ViewSettings(environment=str(path)))
    model.show(DEFAULT_DESIGN)
    panel = _panel(qtbot, model)
    qtbot.waitUntil(lambda: panel.view.basis_current, timeout=60000)
    flat = panel.view.grab_image()
    QTest.mouseClick(panel.stage, Qt.MouseButton.LeftButton)
    assert model.settings.stage is True
    gl_frame = panel.view.grab_image()  # drawn by the core's GL renderer before the worker is done
    panel.view.wait_idle(60000)
    qtbot.waitUntil(lambda: panel.view.basis_current, timeout=60000)
    cached = panel.view.grab_image()
    np.testing.assert_array_equal(cached, panel.view.basis.core.edit(list(model.weights()), 0.0))
    assert np.abs(cached[0, 0].astype(int) - flat[0, 0].astype(int)).max() > 3  # backdrop, not grey
    diff = np.abs(gl_frame.astype(int) - cached.astype(int))
    assert np.median(diff) <= 2 and np.percentile(diff, 99) <= 12  # GL float32 vs NumPy float64 lookups
    panel.close()


@pytest.mark.gl
def test_clear_coat_checkbox(qtbot, own_cache) -> None:
    from ui.models.view import layer_weights

    model = ViewModel()
    model.show(DEFAULT_DESIGN)
    panel = _panel(qtbot, model)
    qtbot.waitUntil(lambda: panel.view.basis_current, timeout=60000)
    before = panel.view.grab_image()
    QTest.mouseClick(panel.coat, Qt.MouseButton.LeftButton)
    assert model.settings.coat is True
    panel.view.wait_idle(60000)
    qtbot.waitUntil(lambda: panel.view.basis_current, timeout=60000)
    basis = panel.view.basis
    assert any(kind == "Cg" for kind, _ in basis.layout)
    after = panel.view.grab_image()
    np.testing.assert_array_equal(after, basis.core.edit(list(model.weights()), 0.0))
    obj = basis.paint >= 0
    assert np.abs(after[obj].astype(int) - before[obj].astype(int)).max() > 3  # grazing gloss rises
    # the GPU composite weights of the split images: Cg constant w_G, Cd times c w_DD
    const, times_c = layer_weights(basis.layout, model.weights()[0])
    w_dd = model.weights()[0].map_weights()[1]
    j = basis.layout.index(next(x for x in basis.layout if x[0] == "Cd"))
    assert const[j] == pytest.approx(0.0) and times_c[j] == pytest.approx(w_dd[basis.layout[j][1]])
    panel.close()
