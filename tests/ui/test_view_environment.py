"""Loading an .hdr/.exr environment in the viewer: the panel's button and file dialog driven by QTest clicks,
the model's ``load_environment`` (for the File menu), and a broken file refused with the view unchanged."""

from __future__ import annotations

import numpy as np
import pytest
from PySide6.QtCore import Qt
from PySide6.QtTest import QTest

from station.render.errors import EnvironmentFileError
from station.render.weights import LobeWeights
from ui.models.document import DEFAULT_DESIGN
from ui.models.view import ViewInputError, ViewModel, ViewSettings
from ui.widgets.render_view import GLRenderView
from ui.widgets.view_panel import ViewPanel

pytestmark = [pytest.mark.qt]


def _weights(model: ViewModel) -> tuple[LobeWeights, LobeWeights]:
    """Lobe weights of the two shown designs (there are designs)."""
    weights = model.weights()
    assert weights is not None
    return weights


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
    assert isinstance(panel.view, GLRenderView)
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
    assert panel.view.basis is not None
    assert panel.view.basis.core.basis is panel.view.environment_prefilter(str(small[1]))
    after = panel.view.grab_image()
    np.testing.assert_array_equal(after, panel.view.basis.core.edit(list(_weights(model)), 0.0))
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
    assert isinstance(panel.view, GLRenderView)
    qtbot.waitUntil(lambda: panel.view.basis_current, timeout=60000)
    flat = panel.view.grab_image()
    QTest.mouseClick(panel.stage, Qt.MouseButton.LeftButton)
    assert model.settings.stage is True
    gl_frame = panel.view.grab_image()  # drawn by the core's GL renderer before the worker is done
    panel.view.wait_idle(60000)
    qtbot.waitUntil(lambda: panel.view.basis_current, timeout=60000)
    cached = panel.view.grab_image()
    assert panel.view.basis is not None
    np.testing.assert_array_equal(cached, panel.view.basis.core.edit(list(_weights(model)), 0.0))
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
    assert isinstance(panel.view, GLRenderView)
    qtbot.waitUntil(lambda: panel.view.basis_current, timeout=60000)
    before = panel.view.grab_image()
    QTest.mouseClick(panel.coat, Qt.MouseButton.LeftButton)
    assert model.settings.coat is True
    panel.view.wait_idle(60000)
    qtbot.waitUntil(lambda: panel.view.basis_current, timeout=60000)
    basis = panel.view.basis
    assert basis is not None
    assert any(kind == "Cg" for kind, _ in basis.layout)
    after = panel.view.grab_image()
    np.testing.assert_array_equal(after, basis.core.edit(list(_weights(model)), 0.0))
    obj = basis.paint >= 0
    assert np.abs(after[obj].astype(int) - before[obj].astype(int)).max() > 3  # grazing gloss rises
    # the GPU composite weights of the split images: Cg constant w_G, Cd times c w_DD
    const, times_c = layer_weights(basis.layout, _weights(model)[0])
    w_dd = _weights(model)[0].map_weights()[1]
    j = basis.layout.index(next(x for x in basis.layout if x[0] == "Cd"))
    assert const[j] == pytest.approx(0.0) and times_c[j] == pytest.approx(w_dd[basis.layout[j][1]])
    panel.close()


@pytest.mark.gl
def test_flakes_checkbox_draws_sparkle_that_averages_away(qtbot, own_cache) -> None:
    """Flakes on: every frame (view change and paint edit) comes from the core's GL renderer with the
    paint's flake layer; 16×16-pixel means stay within ΔE00 0.5 of flakes off (99 % of the blocks); the
    panel says what the level of detail chose."""
    from colour import delta_E

    from station.model import FaceFlopTravelGloss
    from station.model.display import decode_display, display_to_lab, encode_display
    from station.render.flakes import flake_lod

    silver = FaceFlopTravelGloss((90.0, 0.0, 0.0), (30.0, 0.0, 0.0), 60.0, 88.0)
    model = ViewModel(ViewSettings(zoom=4.0))  # close up: flakes larger than the sparkle threshold
    model.show(silver)
    panel = _panel(qtbot, model)
    assert isinstance(panel.view, GLRenderView)
    panel.resize(560, 560)
    qtbot.waitUntil(lambda: panel.view.basis_current, timeout=60000)
    panel.view.wait_idle(60000)
    off = panel.view.grab_image()
    QTest.mouseClick(panel.flakes, Qt.MouseButton.LeftButton)
    assert model.settings.flakes is True
    qtbot.waitUntil(lambda: panel.flake_status.toolTip() != "", timeout=20000)
    h = panel.view._pixel_size()[1]
    expected = flake_lod(panel.view._flake_layer(), model.settings.camera(), h)
    assert panel.flake_status.toolTip() == expected.reason and expected.on, expected.reason
    on = panel.view.grab_image()
    assert panel.view.basis is not None
    obj = panel.view.basis.paint >= 0
    diff = np.abs(on.astype(int) - off.astype(int)).max(axis=-1)
    assert np.mean(diff[obj] > 2) > 0.02  # sparkle: a share of the object's pixels moved
    blocks = [
        (slice(y, y + 16), slice(x, x + 16))
        for y in range(0, on.shape[0] - 15, 16)
        for x in range(0, on.shape[1] - 15, 16)
        if obj[y : y + 16, x : x + 16].all()
    ]
    assert len(blocks) > 20

    def lab(img: np.ndarray, b: tuple[slice, slice]) -> np.ndarray:  # the block's mean light, as Lab
        return display_to_lab(encode_display(decode_display(img[b].reshape(-1, 3) / 255.0).mean(axis=0)))

    de = [float(delta_E(lab(on, b), lab(off, b), method="CIE 2000")) for b in blocks]
    # "off" is the cached-basis (NumPy) frame, "on" the GL frame: the engines' own difference is in these
    # figures too (the core's flakes test holds on against off on one engine to ΔE00 0.5 in every block);
    # a block holding a lamp's glint may pass 0.5 here.
    assert np.percentile(de, 99) <= 0.5 and np.median(de) <= 0.25, np.percentile(de, [50, 99, 100])
    frames = panel.view.gl_frames
    model.show(FaceFlopTravelGloss((80.0, 2.0, -6.0), (30.0, 0.0, -4.0), 60.0, 88.0))  # a paint edit
    qtbot.waitUntil(lambda: panel.view.gl_frames > frames, timeout=20000)
    edited = panel.view.grab_image()
    assert np.abs(edited[obj].astype(int) - on[obj].astype(int)).max() > 3
    QTest.mouseClick(panel.flakes, Qt.MouseButton.LeftButton)
    assert model.settings.flakes is False
    qtbot.waitUntil(lambda: panel.flake_status.toolTip() == "", timeout=20000)
    panel.close()
