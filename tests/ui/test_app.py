"""Main window: every screen present, edits from any screen are undoable from the Edit menu, the
screenshots command writes one PNG per screen, the CLI refuses bad input."""

from __future__ import annotations

import json
import os
import sys
from pathlib import Path

import pytest
from PIL import Image

from tests.processes import run
from ui.app import MainWindow
from ui.models.document import DEFAULT_DESIGN
from ui.models.measure_db import LocalSink

pytestmark = [pytest.mark.qt]


def test_main_window_undo_redo_from_menu(qtbot, tmp_path):
    sink = LocalSink(f"sqlite:///{tmp_path / 'station.sqlite3'}", tmp_path / "outbox.sqlite3")
    win = MainWindow(sink=sink, ask_on_close=False)
    assert win.store.sink is sink
    qtbot.addWidget(win)
    win.resize(1200, 800)
    win.show()
    qtbot.waitExposed(win)
    assert [win.tabs.tabText(i) for i in range(win.tabs.count())] == [
        "Design",
        "Tweaker",
        "Mood board",
        "Library",
        "Instruments",
        "QA",
        "QC",
        "Booth",
        "Formulation",
    ]
    assert not win.undo_action.isEnabled()
    panel = win.designer_panel
    panel.gloss.setValue(30)
    panel.gloss.setValue(20)  # one slider movement …
    win.designer.end_drag()
    panel.variations.buttons[0].click()  # … and a variation
    assert win.document.design.gloss_gu == 20.0
    assert win.view_model.designs is not None and win.view_model.designs[0] == win.document.design
    assert "variation" in win.undo_action.text()
    after_gloss = win.document.undo_label
    win.undo_action.trigger()
    assert win.document.design == DEFAULT_DESIGN.replace(gloss_gu=20.0) and after_gloss
    win.undo_action.trigger()
    assert win.document.design is DEFAULT_DESIGN
    assert win.view_model.designs is not None and win.view_model.designs[0] is DEFAULT_DESIGN
    win.redo_action.trigger()
    assert win.document.design.gloss_gu == 20.0
    assert "gloss 20 GU" in win.statusBar().currentMessage()
    win.view_panel.view.wait_idle()
    win.close()


@pytest.mark.slow
def test_screenshots_command_exits_cleanly(tmp_path):
    """``station viewer screenshots`` run as a user runs it, from a folder outside the checkout: every
    screen written and a clean exit (it used to write them all, then crash in Qt's teardown, exit 139)."""
    out = tmp_path / "shots"
    proc = run(
        [
            str(Path(sys.executable).with_name("station")),
            "viewer",
            "screenshots",
            "--no-scan",
            "--out",
            str(out),
            "--json",
        ],
        cwd=tmp_path,
        timeout=300,
        env={**os.environ, "QT_QPA_PLATFORM": os.environ.get("QT_QPA_PLATFORM", "xcb")},
    )
    assert proc.returncode == 0, proc.stderr[-2000:]
    written = json.loads(proc.stdout)["written"]
    assert len(written) == 8 and all(Path(p).is_file() for p in written)


@pytest.mark.slow
def test_screenshots_of_every_screen(qtbot, tmp_path):
    from ui.screenshots import SIZE, take_screenshots

    paths = take_screenshots(tmp_path, scan=False)
    assert [p.name for p in paths] == [
        "design.png",
        "file-menu.png",
        "tweaker.png",
        "moodboard.png",
        "library.png",
        "instruments.png",
        "qa.png",
        "formulation.png",
    ]
    for p in paths:
        with Image.open(p) as im:
            assert im.size[0] >= SIZE[0] and im.size[1] >= SIZE[1]
            # not a blank capture: many distinct colours
            assert len(im.convert("RGB").getcolors(maxcolors=1 << 20) or []) > 500


def test_cli_viewer_refuses_bad_service_url(capsys):
    from station.cli import main

    assert main(["viewer", "--service", "ftp://nope"]) == 2
    err = capsys.readouterr().err
    assert "--service" in err and len(err.strip().splitlines()) == 1


def test_cli_viewer_refuses_a_token_without_a_service(capsys):
    from station.cli import main

    assert main(["viewer", "--token", "secret"]) == 2
    err = capsys.readouterr().err
    assert "--token" in err and len(err.strip().splitlines()) == 1
