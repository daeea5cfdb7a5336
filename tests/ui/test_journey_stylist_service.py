"""Stylist's day in service mode, against a real ``station serve`` (the demo library, plus a studio
library uploaded to the service only), driven through the real main window with clicks and key presses:
File → Open the stylist's own design file, pick the studio paint from the SERVICE's library on the
Library tab (ColorSnap over the service's listing), edit it (face Lab typed, a variation clicked), store
it on the service (Service → Save current design), File → Save As and Export XML, then File → New and
reopen the saved file, and load the stored design back from the service into the palette.

Expectations: the studio paint's Lab equals the opened design's at 15/45/110° by construction, so its
ΣΔE*ab is 0 and it is the first match (it is not in the local demo library, so only the service's library
can offer it); the stored design read back over HTTP, the saved file and the exported XML hold the edited
face, flop, travel and gloss (the model's definitions: face = Lab at 15°, flop = Lab beyond θ_clamp).
"""

from __future__ import annotations

import json
import xml.etree.ElementTree as ET

import numpy as np
import pytest
from PySide6.QtCore import Qt

from station.formulate.demo import demo_library
from station.model.design_io import save_design
from tests.ui.real_service import paint_csv, station_service
from tests.ui.test_journey_stylist import (
    click_center,
    click_menu_item,
    file_menu,
    show_tab,
    type_into,
    xml_number,
)
from ui.app import MainWindow
from ui.models.document import DEFAULT_DESIGN
from ui.models.measure_db import ServiceSink
from ui.models.service import ServiceClient
from ui.widgets.library_screen import LibraryScreen

pytestmark = [pytest.mark.qt, pytest.mark.slow]
ANGLES = (15.0, 25.0, 45.0, 75.0, 110.0)
LEFT = Qt.MouseButton.LeftButton


def _local(tag: str) -> str:
    return tag.rsplit("}", 1)[-1]


def test_stylist_day_in_service_mode(qtbot, tmp_path):
    brief = DEFAULT_DESIGN.replace(
        name="brief", face=(58.0, -21.0, -30.0), flop=(27.0, -9.0, -18.0), travel_deg=80.0, gloss_gu=86.0
    )
    brief_path = save_design(brief, tmp_path / "brief.json")
    studio = {a: tuple(float(v) for v in brief.lab_at(np.array([a]))[0]) for a in ANGLES}
    assert "STUDIO-1" not in set(demo_library().codes)
    with station_service(tmp_path, "stylist", "chemist") as (base, tokens):
        chemist = ServiceClient(base, tokens["chemist"])
        up = chemist.checked(
            "POST",
            "/library/import",
            params={"name": "studio"},
            content=paint_csv([("STUDIO-1", "metallic", brief.gloss_gu, studio)]),
            headers={"Content-Type": "text/csv"},
        )
        assert up.status_code == 201
        chemist.close()
        service = ServiceClient(base, tokens["stylist"], timeout_s=60.0)
        win = MainWindow(service=service, sink=ServiceSink(service, tmp_path / "outbox.sqlite3"))
        try:
            win.resize(1500, 950)
            win.move(0, 0)
            win.show()
            qtbot.waitExposed(win)
            win.activateWindow()
            qtbot.waitUntil(win.isActiveWindow)
            doc = win.document
            # --- File → Open the stylist's own design
            file_menu(qtbot, win, "Open design", brief_path)
            assert doc.design == brief and doc.name == "brief" and win.files.unsaved() == []
            # --- the service's library on the Library tab: ColorSnap, the studio paint first, use it
            lib_screen = show_tab(qtbot, win, "Library")
            assert isinstance(lib_screen, LibraryScreen)
            lib = lib_screen.model.library
            assert base in lib_screen.title.text() and len(lib) == 6001  # the demo's 6000 and the upload
            qtbot.waitUntil(lambda: lib_screen.idle, timeout=120000)  # thumbnails of 6001 paints
            click_center(qtbot, lib_screen.snap_btn)
            qtbot.waitUntil(lambda: lib_screen.idle, timeout=60000)  # ColorSnap runs in the background
            result = lib_screen.model.snap_result
            assert result is not None and result.matches[0].code == "STUDIO-1"
            assert result.matches[0].sum_de == pytest.approx(0.0, abs=1e-3)
            item = lib_screen.matches.item(0)
            qtbot.mouseClick(
                lib_screen.matches.viewport(),
                LEFT,
                pos=lib_screen.matches.visualItemRect(item).center(),
            )
            click_center(qtbot, lib_screen.use_btn)
            assert doc.undo_label == "ColorSnap STUDIO-1"
            picked = doc.design
            assert picked.gloss_gu == pytest.approx(brief.gloss_gu, abs=1e-9)
            # the fit to the paint's five angles passes near the brief at every angle
            err = np.linalg.norm(picked.lab_at(np.array(ANGLES)) - brief.lab_at(np.array(ANGLES)), axis=-1)
            assert float(err.max()) < 3.0
            show_tab(qtbot, win, "Design")
            # --- edit: the face Lab typed, then the "lighter" variation clicked
            panel = win.designer_panel
            type_into(qtbot, panel.lab_edits["face"], "60, -24, -33")
            assert doc.design.face == (60.0, -24.0, -33.0)
            grid = panel.variations
            lighter = grid.buttons[0]
            assert lighter.text() == "lighter"
            click_center(qtbot, lighter)
            step = grid.degree.value()
            assert doc.design.face == pytest.approx((60.0 + step, -24.0, -33.0), abs=1e-9)
            edited = doc.design
            # --- store it on the service; the service returns the same design
            click_menu_item(qtbot, win, "&Service", "Save current design")
            assert "saved as design" in win.statusBar().currentMessage()
            rows = service.call("GET", "/designs")["data"]
            (stored,) = [r for r in rows if r["name"] == "brief"]
            d = stored["design"]
            assert d["face"] == pytest.approx(list(edited.face), abs=1e-9)
            assert d["flop"] == pytest.approx(list(edited.flop), abs=1e-9)
            assert (d["travel_deg"], d["gloss_gu"]) == pytest.approx((edited.travel_deg, edited.gloss_gu))
            # --- File → Save As and Export XML
            saved_path, xml_path = tmp_path / "studio-blue.json", tmp_path / "studio-blue.xml"
            file_menu(qtbot, win, "Save As design", saved_path)
            assert win.files.unsaved() == [] and win.files.paths["design"] == saved_path
            data = json.loads(saved_path.read_text())
            assert data["face"] == list(edited.face) and data["flop"] == list(edited.flop)
            file_menu(qtbot, win, "Export design as XML", xml_path)
            root = ET.fromstring(xml_path.read_bytes())
            labs = {
                xml_number(el.get("aspecularDeg")): (
                    xml_number(el.get("L")),
                    xml_number(el.get("a")),
                    xml_number(el.get("b")),
                )
                for el in root.iter()
                if _local(el.tag) == "lab"
            }
            assert labs[15.0] == pytest.approx(edited.face, abs=1e-4)
            assert labs[110.0] == pytest.approx(edited.flop, abs=1e-4)  # beyond θ_clamp = 80°
            # --- File → New, then reopen the saved file; the stored design comes back into the palette
            file_menu(qtbot, win, "New design")
            assert doc.design == DEFAULT_DESIGN
            file_menu(qtbot, win, "Open design", saved_path)
            assert doc.design.face == edited.face and doc.design.flop == edited.flop
            assert doc.design.gloss_gu == edited.gloss_gu and win.files.paths["design"] == saved_path
            click_menu_item(qtbot, win, "&Service", "Load designs into palette")
            assert [p.face for _n, p in win.designer.palette] == [edited.face]
            win.view_panel.view.wait_idle()
            win.ask_on_close = False  # the palette loaded from the service is not a file of its own
            win.close()
            assert not win.isVisible()
        finally:
            if win.isVisible():
                win.ask_on_close = False
                win.view_panel.view.wait_idle()
                win.close()
            service.close()
