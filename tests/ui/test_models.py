"""Qt-free view models: undo/redo exactness, merging, refusal, view settings, basis composite."""

from __future__ import annotations

import numpy as np
import pytest

from station.errors import InputError
from station.model import FaceFlopTravelGloss
from station.render.numpy_renderer import render_linear
from ui.models.designer import DesignerModel
from ui.models.document import DEFAULT_DESIGN, DesignDocument
from ui.models.events import EventGroup
from ui.models.view import BasisImages, ViewInputError, ViewSettings, environment_basis, paint_weights


def test_undo_restores_the_exact_design_object():
    doc = DesignDocument()
    model = DesignerModel(doc)
    start = doc.design
    assert model.set_gloss(30.0)
    after_gloss = doc.design
    assert model.move_face(20.0, -10.0)
    assert doc.design.face[1:] == (20.0, -10.0)
    assert doc.undo()
    assert doc.design is after_gloss
    assert doc.undo()
    assert doc.design is start and doc.design == DEFAULT_DESIGN
    assert not doc.undo()
    assert doc.redo() and doc.design is after_gloss


def test_drag_merges_into_one_undo_step_until_release():
    doc = DesignDocument()
    model = DesignerModel(doc)
    for g in (80.0, 70.0, 60.0):
        model.set_gloss(g)
    model.end_drag()
    model.set_gloss(10.0)
    assert doc.design.gloss_gu == 10.0
    doc.undo()
    assert doc.design.gloss_gu == 60.0
    doc.undo()
    assert doc.design == DEFAULT_DESIGN and not doc.can_undo


def test_refused_edit_leaves_design_and_reports_the_field():
    doc = DesignDocument()
    errors: list[str] = []
    doc.events.error.connect(errors.append)
    assert not DesignerModel(doc).set_gloss(150.0)
    assert doc.design == DEFAULT_DESIGN and not doc.can_undo
    assert len(errors) == 1 and "gloss_gu" in errors[0]


def test_hsb_is_relative_to_the_drag_start():
    doc = DesignDocument()
    model = DesignerModel(doc)
    model.set_hsb(90.0, 1.0, 0.0)
    model.set_hsb(180.0, 1.0, 0.0)  # not 270: relative to the base
    a, b = DEFAULT_DESIGN.face[1:]
    np.testing.assert_allclose(doc.design.face[1:], (-a, -b), atol=1e-9)
    model.end_drag()
    doc.undo()
    assert doc.design == DEFAULT_DESIGN


def test_point_drag_refits_through_the_model():
    doc = DesignDocument()
    model = DesignerModel(doc)
    assert model.move_point("L", 15.0, 70.0)
    # the 5-point least-squares refit moves the 15° value towards the dragged point
    assert doc.design.lab_at(15.0)[0] > DEFAULT_DESIGN.lab_at(15.0)[0] + 3.0


def test_events_disconnect_by_owner():
    class Owner:
        def __init__(self):
            self.calls = 0

        def cb(self, *a):
            self.calls += 1

    g = EventGroup("x")
    o = Owner()
    g.x.connect(o.cb)
    g.x.emit()
    with g.x.blocker():
        g.x.emit()
    g.disconnect_all(o)
    g.x.emit()
    assert o.calls == 1


def test_view_settings_validate_and_orbit_keeps_distance():
    with pytest.raises(ViewInputError) as e:
        ViewSettings(exposure_ev=20.0)
    assert isinstance(e.value, InputError) and "exposure_ev" in str(e.value)
    with pytest.raises(ViewInputError):
        ViewSettings(shape="teapot")
    base = ViewSettings()
    np.testing.assert_allclose(base.camera().eye, (0.0, 0.8, 4.5), atol=1e-12)
    turned = base.replace(yaw_deg=90.0).camera()
    assert np.linalg.norm(turned.eye) == pytest.approx(np.linalg.norm((0.0, 0.8, 4.5)))
    assert turned.eye[0] == pytest.approx(4.5, rel=1e-9) and turned.eye[2] == pytest.approx(0.0, abs=1e-9)
    assert np.linalg.norm(base.replace(zoom=2.0).camera().eye) == pytest.approx(np.hypot(0.8, 4.5) / 2)


def test_basis_composite_equals_the_core_numpy_renderer():
    """Re-weighting cached basis images is the same sum as station.render's reference renderer."""
    s = ViewSettings(shape="cylinder")
    basis = BasisImages.compute(s, 48, 40)
    a, b = (
        paint_weights(DEFAULT_DESIGN),
        paint_weights(FaceFlopTravelGloss((40, 50, 20), (20, 30, 10), 60, 20)),
    )
    ours = basis.composite_linear((a, b))
    ref = render_linear(s.scene(), environment_basis("booth"), [a, b], 48, 40)
    np.testing.assert_allclose(ours, ref, rtol=1e-5, atol=1e-6)


def test_stored_lists_offer_the_45_degree_block_only(tmp_path) -> None:
    """A two-illumination file stores its 15° block as its own row; the QA and job-history lists (the
    sink's ``recent``) offer 45° readings only, so a 15° block is never judged as a 45° one."""
    from station.ingest import Reading
    from tests.ingest._readings import make_reading
    from ui.models.measure_db import LocalSink, PanelInfo

    sink = LocalSink(f"sqlite:///{tmp_path / 'station.sqlite3'}", tmp_path / "outbox.sqlite3")
    sink.prepare()
    panel = PanelInfo("J-45", "bumper")
    r45 = make_reading(7, 0)
    fields = make_reading(7, 1).model_dump()
    fields["illumination_deg"] = 15
    r15 = Reading(**fields)
    assert sink.submit(panel, r45).status == "stored" and sink.submit(panel, r15).status == "stored"
    rows = sink.recent(10)
    assert len(rows) == 1 and rows[0].label == "J-45 bumper"
    assert rows[0].lab.tolist() == [list(map(float, row)) for row in r45.lab]
    sink.close()


def test_swatch_basis_is_the_view_at_the_grid_points_and_a_swatch_its_box_filter():
    """The sampled basis re-weighted equals the full view's frame read at the grid points (brute force:
    the grid laid out here from the object's bounding box), and a swatch is its s × s mean, encoded."""
    from station.render.tonemap import to_display
    from ui.models.designer import SWATCH_MARGIN, SwatchInputError, VariationSwatches, swatch_basis

    settings = ViewSettings(shape="speedshape", yaw_deg=-15.0)
    view = BasisImages.compute(settings, 160, 120, prefilter_size=16).core
    w = paint_weights(DEFAULT_DESIGN)
    full = view.linear_image([w, w])  # (120, 160, 3)
    size = 20
    sub = swatch_basis(view, size, supersample=3)
    ys, xs = np.divmod(view.pixels, view.width)
    side = max(xs.max() + 1 - xs.min(), ys.max() + 1 - ys.min()) * (1 + 2 * SWATCH_MARGIN)
    s = min(3, int(side // size))
    n = size * s
    assert sub.width == sub.height == n
    t = (np.arange(n) + 0.5) / n - 0.5
    gx = np.clip(np.floor((xs.min() + xs.max() + 1) / 2 + t * side), 0, 159).astype(int)
    gy = np.clip(np.floor((ys.min() + ys.max() + 1) / 2 + t * side), 0, 119).astype(int)
    expect = full[gy[:, None], gx[None, :]]
    assert np.allclose(sub.linear_image([w, w]), expect, rtol=1e-5, atol=1e-6)
    sw = VariationSwatches(size, supersample=3)
    sw.use(view)
    box = expect.reshape(size, s, size, s, 3).mean(axis=(1, 3))
    assert np.array_equal(sw.render(DEFAULT_DESIGN), to_display(box, 0.0))
    # a lighter design gives a lighter swatch on the object pixels, the background unchanged
    lighter = DEFAULT_DESIGN.replace(face=(DEFAULT_DESIGN.face[0] + 10, *DEFAULT_DESIGN.face[1:]))
    a, b = sw.render(DEFAULT_DESIGN).astype(int), sw.render(lighter).astype(int)
    assert (b.sum(-1) >= a.sum(-1) - 1).all() and (b.sum(-1) > a.sum(-1) + 3).mean() > 0.1
    with pytest.raises(SwatchInputError, match="size"):
        swatch_basis(view, 2)
    with pytest.raises(SwatchInputError, match="source"):
        VariationSwatches(10).render(DEFAULT_DESIGN)
