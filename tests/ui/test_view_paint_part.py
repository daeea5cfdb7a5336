"""The paint part of an own model in the viewer: a GLB written here with trimesh (a body, four wheels and a
windscreen, each its own mesh and material); the view panel's part picker lists the file's mesh and
material names, and picking the body (keyboard, QTest) paints the body alone, the wheels drawn as tyres and
the windscreen as glass (their names), as ``station render --mesh … --paint`` does."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh
from PySide6.QtCore import Qt
from PySide6.QtTest import QTest

from station.render.errors import RenderInputError
from station.render.mesh_parts import GLASS, PAINT, TYRE
from ui.models.document import DEFAULT_DESIGN
from ui.models.view import ViewModel
from ui.widgets.view_panel import ViewPanel

pytestmark = [pytest.mark.qt]


@pytest.fixture
def own_cache(tmp_path, monkeypatch):
    monkeypatch.setenv("CACAD_CACHE_DIR", str(tmp_path / "cache"))


def _material(name: str) -> trimesh.visual.material.PBRMaterial:
    return trimesh.visual.material.PBRMaterial(name=name, baseColorFactor=[200, 200, 200, 255])


@pytest.fixture
def car_glb(tmp_path):
    """body (material CarPaint, 12 triangles), wheel_0..3 (material Rubber, cylinders), windscreen (Glass)."""
    scene = trimesh.Scene()
    body = trimesh.creation.box(extents=(2.0, 0.6, 1.0))
    body.visual = trimesh.visual.TextureVisuals(material=_material("CarPaint"))
    scene.add_geometry(body, node_name="body", geom_name="body")
    for i, (x, z) in enumerate(((-0.7, -0.55), (0.7, -0.55), (-0.7, 0.55), (0.7, 0.55))):
        wheel = trimesh.creation.cylinder(radius=0.3, height=0.2, sections=16)
        wheel.apply_transform(trimesh.transformations.rotation_matrix(np.pi / 2, (1, 0, 0)))
        wheel.apply_translation((x, -0.3, z))
        wheel.visual = trimesh.visual.TextureVisuals(material=_material("Rubber"))
        scene.add_geometry(wheel, node_name=f"wheel_{i}", geom_name=f"wheel_{i}")
    screen = trimesh.creation.box(extents=(0.05, 0.35, 0.8))
    screen.apply_translation((0.5, 0.45, 0.0))
    screen.visual = trimesh.visual.TextureVisuals(material=_material("Glass"))
    scene.add_geometry(screen, node_name="windscreen", geom_name="windscreen")
    path = tmp_path / "car.glb"
    scene.export(path)
    return path, {"body": len(body.faces), "wheels": 4 * len(wheel.faces), "screen": len(screen.faces)}


def _face_codes(mesh) -> np.ndarray:
    return np.asarray(mesh.painted)[np.asarray(mesh.faces)[:, 0]]


@pytest.mark.gl
def test_picking_the_body_paints_it_alone(qtbot, car_glb, own_cache) -> None:
    path, faces = car_glb
    model = ViewModel()
    model.show(DEFAULT_DESIGN)
    panel = ViewPanel(model)
    qtbot.addWidget(panel)
    panel.resize(640, 420)
    panel.show()
    qtbot.waitExposed(panel)
    combo = panel.paint_part
    assert not combo.isEnabled()  # a built-in shape has no parts
    assert panel.open_model(str(path))
    names = [combo.itemText(i) for i in range(combo.count())]
    assert combo.isEnabled() and names[0] == "every part"
    assert {"body", "CarPaint", "Rubber", "Glass", "windscreen", "wheel_0", "wheel_3"} <= set(names[1:])
    every = _face_codes(model.mesh())
    assert np.all(every == PAINT)  # no part picked: every part painted
    frames = panel.view.gl_frames
    combo.setFocus()
    for _ in range(names.index("body")):  # keyboard: down to "body"
        QTest.keyClick(combo, Qt.Key.Key_Down)
    assert combo.currentText() == "body" and model.settings.paint_part == "body"
    codes = _face_codes(model.mesh())
    assert codes.size == sum(faces.values())
    assert np.count_nonzero(codes == PAINT) == faces["body"]
    assert np.count_nonzero(codes == TYRE) == faces["wheels"]
    assert np.count_nonzero(codes == GLASS) == faces["screen"]
    qtbot.waitUntil(lambda: panel.view.gl_frames > frames, timeout=20000)  # the view drew the new parts
    # by material name: the same parts
    assert np.array_equal(_face_codes(model.set_paint_part("CarPaint")), codes)
    assert combo.currentText() == "CarPaint"
    # a name no part has: refused, naming the field and listing the parts; the view unchanged
    with pytest.raises(RenderInputError) as err:
        model.set_paint_part("bonnet")
    assert err.value.field == "paint" and "wheel_0" in str(err.value)
    assert model.settings.paint_part == "CarPaint"
    # back to a built-in shape: no parts to pick
    panel.shape.setCurrentIndex(0)
    assert not combo.isEnabled() and model.settings.paint_part is None and model.mesh() is None
    panel.close()
