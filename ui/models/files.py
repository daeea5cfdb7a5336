"""The stylist's files (Qt-free): New / Open / Save / Save As of the design, the palette and the mood
board, export of the design as thesis XML or CxF3, and which of them has unsaved changes.

Formats are the core's: designs ``cacad.design/1`` (:mod:`station.model.design_io`), palettes
``cacad.palette/1`` (:mod:`station.design.palette`), mood boards ``cacad.moodboard/1``
(:class:`station.design.moodboard.MoodBoard`); exports go through
:func:`station.formulate.export.export_specs` like the CLI's ``formulate export`` and the service.

A kind is *unsaved* when its current value differs from the value last opened, saved or made new
(so undoing back to the saved design makes it clean again). A file that cannot be read raises
:class:`FileInputError` naming the file and leaves everything as it was.
"""

from __future__ import annotations

from pathlib import Path
from typing import Literal

from station.design.moodboard import Board, MoodBoard
from station.design.palette import PaletteEntries, load_palette, save_palette
from station.errors import InputError
from station.model import FaceFlopTravelGloss
from station.model.design_io import load_design, save_design
from ui.models.designer import DesignerModel
from ui.models.document import DEFAULT_DESIGN, DesignDocument
from ui.models.moodboard import MoodBoardModel

Kind = Literal["design", "palette", "moodboard"]
KINDS: tuple[Kind, ...] = ("design", "palette", "moodboard")
#: Export formats and their file suffix.
EXPORTS = {"xml": ".xml", "cxf": ".cxf"}
TITLES = {"design": "design", "palette": "palette", "moodboard": "mood board"}


class FileInputError(InputError):
    """A file the viewer cannot open or write (the field is the file kind, the detail the reason)."""


class StylistFiles:
    """Paths and saved states of the design, palette and mood board of one window."""

    def __init__(self, document: DesignDocument, designer: DesignerModel, moodboard: MoodBoardModel) -> None:
        self.document = document
        self.designer = designer
        self.moodboard = moodboard
        self.paths: dict[Kind, Path | None] = dict.fromkeys(KINDS)
        self._saved: dict[Kind, object] = {k: self._value(k) for k in KINDS}

    def _value(self, kind: Kind) -> object:
        if kind == "design":
            return (self.document.design, self.document.name)
        if kind == "palette":
            return tuple(self.designer.palette)
        return self.moodboard.moodboard

    def _mark_saved(self, kind: Kind, path: Path | None) -> None:
        self.paths[kind] = path
        self._saved[kind] = self._value(kind)

    def unsaved(self) -> list[Kind]:
        """Kinds whose current value differs from the one last opened, saved or made new."""
        return [k for k in KINDS if self._value(k) != self._saved[k]]

    # ------------------------------------------------------------------ new
    def new(self, kind: Kind) -> None:
        """Start a new design (the default design, undoable), an empty palette or an empty mood board."""
        if kind == "design":
            self.document.set_design(DEFAULT_DESIGN, "new design")
            self.document.name = "untitled"
        elif kind == "palette":
            self.designer.palette = []
            self.designer.events.palette.emit()
        else:
            self.moodboard.load(MoodBoard((Board("board 1"),)))
        self._mark_saved(kind, None)

    # ------------------------------------------------------------------ open
    def open(self, kind: Kind, path: str | Path) -> None:
        """Read *path* as a *kind* file and make it current; nothing changes when it cannot be read."""
        p = Path(path)
        try:
            if kind == "design":
                design = load_design(p)
                self.document.set_design(design, f"open {p.name}")
                self.document.name = design.name or p.stem
            elif kind == "palette":
                entries = load_palette(p)
                self.designer.palette = list(entries)
                self.designer.events.palette.emit()
            else:
                try:
                    text = p.read_text(encoding="utf-8")
                except (OSError, UnicodeDecodeError) as exc:
                    raise FileInputError("moodboard", "a readable mood-board file", str(p), str(exc)) from exc
                self.moodboard.load(MoodBoard.from_json(text), p.parent)
        except FileInputError:
            raise
        except (InputError, ValueError) as exc:
            raise FileInputError(kind, f"a {TITLES[kind]} file", p.name, str(exc)) from exc
        self._mark_saved(kind, p)

    # ------------------------------------------------------------------ save
    def save(self, kind: Kind, path: str | Path | None = None) -> Path:
        """Write *kind* to *path* (default: where it was last opened or saved)."""
        target = Path(path) if path is not None else self.paths[kind]
        if target is None:
            raise FileInputError(kind, "a file name (use Save As)", None)
        try:
            if kind == "design":
                name = self.document.name if self.document.name != "untitled" else target.stem
                self.document.name = name
                save_design(self.document.design.replace(name=name), target)
            elif kind == "palette":
                save_palette(self.designer.palette, target)
            else:
                self.moodboard.moodboard.save(target)
        except OSError as exc:
            raise FileInputError(kind, "a writable file", str(target), str(exc)) from exc
        self._mark_saved(kind, target)
        return target

    # ------------------------------------------------------------------ export
    def export(self, fmt: str, path: str | Path) -> Path:
        """Write the current design as thesis XML (``xml``) or CxF3 (``cxf``) at both 3-angle sets and the
        5-angle set (:func:`station.formulate.export.export_specs`)."""
        from station.formulate.color_xml import colors_to_xml
        from station.formulate.cxf import specs_to_cxf
        from station.formulate.export import export_specs

        if fmt not in EXPORTS:
            raise FileInputError("format", " | ".join(EXPORTS), fmt)
        design = self.current_design()
        specs, _ = export_specs(design, five_angles=True)
        data = colors_to_xml(specs) if fmt == "xml" else specs_to_cxf(specs)
        p = Path(path)
        try:
            p.write_bytes(data)
        except OSError as exc:
            raise FileInputError(fmt, "a writable file", str(p), str(exc)) from exc
        return p

    def current_design(self) -> FaceFlopTravelGloss:
        """The current design carrying the document's name."""
        name = self.document.name if self.document.name != "untitled" else "design"
        return self.document.design.replace(name=name)

    def palette_entries(self) -> PaletteEntries:
        """The palette as (name, design) pairs."""
        return list(self.designer.palette)
