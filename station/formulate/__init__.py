"""Formulation bridge (thesis §5.3; docs/design.md §6): colour libraries, ColorSnap, recipe formulation,
the closed loop, and the thesis XML / CxF3 exchange. See docs/formulate.md.

The colorant database, the demo library and the spray-out panels are SYNTHETIC and say so wherever
they appear. Everything here is plain functions and dataclasses (no database, no drivers).
"""

from station.formulate.closed_loop import FormulationJob, LoopStep, closed_loop
from station.formulate.color_xml import (
    ColorSpec,
    colors_to_xml,
    read_color_xml,
    spec_from_design,
    spec_from_lab,
)
from station.formulate.colorants import ColorantDatabase, default_database, predict_gloss, predict_lab
from station.formulate.cxf import library_to_cxf, read_cxf_specs, read_library_cxf, specs_to_cxf
from station.formulate.demo import demo_library, generate_library
from station.formulate.errors import (
    FormulateError,
    FormulateInputError,
    HostileXMLError,
    LibraryFormatError,
    NotFormulableError,
    XMLFormatError,
)
from station.formulate.formulation import (
    FormulationOptions,
    FormulationResult,
    formulate,
    formulate_from_library,
)
from station.formulate.library import Library, LibraryFilter, Paint, classify, hierarchy_counts
from station.formulate.library_csv import read_library_csv, write_library_csv
from station.formulate.munsell import munsell_library
from station.formulate.selection import RecipeOption
from station.formulate.snap import SnapIndex, SnapMatch, SnapResult, brute_force, color_snap, view_data
from station.formulate.sprayout import SprayOutModel

__all__ = [
    "ColorSpec",
    "ColorantDatabase",
    "FormulateError",
    "FormulateInputError",
    "FormulationJob",
    "FormulationOptions",
    "FormulationResult",
    "HostileXMLError",
    "Library",
    "LibraryFilter",
    "LibraryFormatError",
    "LoopStep",
    "NotFormulableError",
    "Paint",
    "RecipeOption",
    "SnapIndex",
    "SnapMatch",
    "SnapResult",
    "SprayOutModel",
    "XMLFormatError",
    "brute_force",
    "classify",
    "closed_loop",
    "color_snap",
    "colors_to_xml",
    "default_database",
    "demo_library",
    "formulate",
    "formulate_from_library",
    "generate_library",
    "hierarchy_counts",
    "library_to_cxf",
    "munsell_library",
    "predict_gloss",
    "predict_lab",
    "read_color_xml",
    "read_cxf_specs",
    "read_library_csv",
    "read_library_cxf",
    "spec_from_design",
    "spec_from_lab",
    "specs_to_cxf",
    "view_data",
    "write_library_csv",
]
