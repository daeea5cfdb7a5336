"""The stylist's files without a display: a mood board whose image is gone, a bad design and a palette
written elsewhere are refused naming the file, and nothing open is changed; option limits are enforced."""

from __future__ import annotations

import json

import pytest

from station.design.moodboard import Board, BoardImage, MoodBoard
from station.errors import InputError
from ui.demo import patch_image
from ui.models.designer import DesignerModel
from ui.models.document import DEFAULT_DESIGN, DesignDocument
from ui.models.files import FileInputError, StylistFiles
from ui.models.moodboard import MoodBoardModel


@pytest.fixture
def files(tmp_path):
    doc = DesignDocument()
    return StylistFiles(doc, DesignerModel(doc), MoodBoardModel(doc))


def test_board_with_a_missing_image_changes_nothing(files, tmp_path):
    img = patch_image(tmp_path / "one.png", ((0.5, 0.5, 0.5),), size=8)
    files.moodboard.add_image(str(img), 3.0, 4.0)
    before = files.moodboard.moodboard
    board = MoodBoard((Board("b", (BoardImage("one.png"), BoardImage("gone.png"))),))
    (tmp_path / "board.json").write_text(board.to_json())
    with pytest.raises(FileInputError) as exc:
        files.open("moodboard", tmp_path / "board.json")
    assert exc.value.field == "moodboard" and "board.json" in str(exc.value)
    assert files.moodboard.moodboard is before and files.paths["moodboard"] is None
    # relative image paths are read against the board file's folder
    ok = MoodBoard((Board("b", (BoardImage("one.png", 1.0, 2.0, 0.5),)),))
    (tmp_path / "ok.json").write_text(ok.to_json())
    files.open("moodboard", tmp_path / "ok.json")
    assert files.moodboard.board.images == (BoardImage(str(tmp_path / "one.png"), 1.0, 2.0, 0.5),)
    assert files.unsaved() == []


def test_bad_design_and_unsaved_tracking(files, tmp_path):
    bad = tmp_path / "d.json"
    bad.write_text(json.dumps({"face": [50, 0, 0], "flop": [40, 0, 0], "travel_deg": 5}))
    with pytest.raises(FileInputError, match="travel"):
        files.open("design", bad)
    assert files.document.design is DEFAULT_DESIGN and not files.document.can_undo
    files.designer.set_gloss(20.0)
    assert files.unsaved() == ["design"]
    files.document.undo()  # back to what was opened: saved again
    assert files.unsaved() == []
    with pytest.raises(FileInputError, match="Save As"):
        files.save("palette")
    with pytest.raises(FileInputError, match="format"):
        files.export("pdf", tmp_path / "x.pdf")
    with pytest.raises(FileInputError, match="writable"):
        files.save("design", tmp_path / "no" / "such" / "dir.json")


def test_eyedropper_option_limits(files):
    m = files.moodboard
    for bad in (-1, 65, 2.5, True):
        with pytest.raises(InputError, match="radius"):
            m.radius = bad
    for bad in (0.0, 1.5):
        with pytest.raises(InputError, match="weight"):
            m.gloss_weight = bad
    m.radius, m.gloss_weight = 0, 1.0
    assert (m.radius, m.gloss_weight) == (0, 1.0)
