"""One entry point for a library file: CSV, CxF3 or the thesis's colour XML, told apart by content.

``.csv`` files are library CSV (:mod:`station.formulate.library_csv`). An ``.xml`` or ``.cxf`` file is
CxF3 (:mod:`station.formulate.cxf`) when its root element is in the CxF3-core namespace and the thesis
XML (:mod:`station.formulate.color_xml`, §5.3.1) when it is in ``urn:cacad-station:color:1``; anything
else is refused naming the root element found.

The thesis XML describes colours, not a library: each ``<color>`` becomes one paint with its Lab at every
angle its measurement sets hold (every colour must hold 15°, 45° and 110° and the same angles as the
others), its 60° gloss and its ``type``; a colour without a ``type`` is ``solid`` when its Lab is the same
at every angle (within :data:`SOLID_SPREAD` ΔE*ab) and ``metallic`` otherwise. The library is synthetic
when every colour says ``synthetic="true"``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from station.formulate.color_xml import NAMESPACE as COLOR_XML_NAMESPACE
from station.formulate.color_xml import ColorSpec, read_color_xml
from station.formulate.cxf import read_library_cxf
from station.formulate.errors import LibraryFormatError, XMLFormatError
from station.formulate.library import STANDARD_ANGLES, Library
from station.formulate.library_csv import read_library_csv
from station.formulate.safe_xml import parse_xml
from station.model.cxf_names import NAMESPACE as CXF_NAMESPACE

#: Largest ΔE*ab between angles of a colour read as ``solid`` when the file gives no type.
SOLID_SPREAD = 0.5
#: Bytes read to tell the two XML kinds apart.
SNIFF_BYTES = 64 << 20


def xml_kind(path: str | Path) -> str:
    """``"cxf"`` or ``"color_xml"`` by the root element's namespace; :class:`XMLFormatError` otherwise."""
    root = parse_xml(Path(path), SNIFF_BYTES)
    ns = root.tag[1:].split("}", 1)[0] if root.tag.startswith("{") else ""
    if ns == CXF_NAMESPACE:
        return "cxf"
    if ns == COLOR_XML_NAMESPACE:
        return "color_xml"
    raise XMLFormatError(
        "root", f"a CxF3 root (namespace {CXF_NAMESPACE}) or <colors> in {COLOR_XML_NAMESPACE}", root.tag
    )


def library_from_specs(specs: list[ColorSpec], name: str) -> Library:
    """A library of the thesis XML's colours (see the module docstring for the rules)."""
    angle_sets = []
    labs: list[dict[float, tuple[float, float, float]]] = []
    for spec in specs:
        lab: dict[float, tuple[float, float, float]] = {}
        for s in spec.sets:
            for a, row in zip(s.angles_deg, np.asarray(s.lab), strict=True):
                lab[float(a)] = (float(row[0]), float(row[1]), float(row[2]))
        labs.append(lab)
        angle_sets.append(tuple(sorted(lab)))
    angles = angle_sets[0]
    for spec, got in zip(specs, angle_sets, strict=True):
        if got != angles:
            raise XMLFormatError(f"color[{spec.name}]", f"Lab at the angles {list(angles)}", list(got))
        if not set(STANDARD_ANGLES) <= set(got):
            raise XMLFormatError(f"color[{spec.name}]", "Lab at 15, 45 and 110 degrees", list(got))
    order = list(STANDARD_ANGLES) + [a for a in angles if a not in STANDARD_ANGLES]
    codes = [spec.code or spec.name for spec in specs]
    if len(set(codes)) != len(codes):
        raise XMLFormatError("color@code", "unique codes (or names)", len(codes) - len(set(codes)))
    matrix = np.array([[lab[a] for a in order] for lab in labs], dtype=np.float64)
    types = []
    for spec, rows in zip(specs, matrix, strict=True):
        if spec.paint_type:
            types.append(spec.paint_type)
        else:
            spread = float(np.linalg.norm(rows[:, None, :] - rows[None, :, :], axis=-1).max())
            types.append("solid" if spread <= SOLID_SPREAD else "metallic")
    return Library(
        name=name,
        codes=np.asarray(codes),
        types=np.asarray(types),
        gloss_gu=np.asarray([spec.gloss_gu for spec in specs]),
        angles_deg=tuple(order),
        lab=matrix,
        synthetic=all(spec.synthetic for spec in specs),
        source="color_xml",
    )


def read_library_file(path: str | Path, name: str | None = None) -> Library:
    """Read a library from a ``.csv``, ``.cxf`` or ``.xml`` file (see the module docstring)."""
    path = Path(path)
    suffix = path.suffix.lower()
    if not path.is_file():
        raise LibraryFormatError(None, None, "an existing library file", str(path))
    if suffix == ".csv":
        return read_library_csv(path, name=name)
    if suffix in (".cxf", ".xml"):
        if xml_kind(path) == "cxf":
            return read_library_cxf(path, name=name)
        return library_from_specs(read_color_xml(path), name or path.stem)
    raise LibraryFormatError(None, None, "a .csv, .cxf or .xml library file", path.name)
