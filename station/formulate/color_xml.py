"""The thesis's colour XML (§5.3.1): import, export, schema.

"Color appearance is specified with standard D65 illumination at 45° from normal … 3 or 5 CIE Lab
tristimulus values as well as the aspecular angles of each value … a single number for standard
gloss." The thesis gives no schema; ours is ``station/formulate/schemas/cacad_color.xsd``
(namespace ``urn:cacad-station:color:1``)::

    <colors xmlns="urn:cacad-station:color:1" version="1">
      <color name="Red metallic" role="design" type="metallic">
        <conditions illuminant="D65" observer="CIE 1964 10 Degree Standard Observer" illuminationAngleDeg="45"/>
        <gloss geometryDeg="60" unit="GU">85.0000</gloss>
        <measurementSet angles="15 45 110"> <lab aspecularDeg="15" L="…" a="…" b="…"/> … </measurementSet>
        <measurementSet angles="25 45 75"> … </measurementSet>
      </color>
    </colors>

Both 3-angle sets (15/45/110 and 25/45/75) are exported for every colour, plus the 5-angle set
(15/25/45/75/110) on request. Stated precision: 4 decimals for Lab and gloss; import(export(x))
equals x rounded to 1e-4 and export(import(export(x))) is byte-identical. Reading goes through
:func:`station.formulate.safe_xml.parse_xml` (no DTD, no entities, ≤ 1 MiB).
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET  # building only; parsing goes through defusedxml
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from station.formulate.errors import XMLFormatError
from station.formulate.library import PAINT_TYPES
from station.formulate.safe_xml import parse_xml
from station.model import ANGLES_3, ANGLES_3_ALT, ANGLES_5, AspecularMeasurements, FaceFlopTravelGloss
from station.model.domain import LAB_CHANNELS, LAB_RANGES

NAMESPACE = "urn:cacad-station:color:1"
SCHEMA_PATH = Path(__file__).with_name("schemas") / "cacad_color.xsd"
MAX_XML_BYTES = 1 << 20
OBSERVER = "CIE 1964 10 Degree Standard Observer"
ROLES = ("design", "match", "measured", "prediction")
DECIMALS = 4
_NS = f"{{{NAMESPACE}}}"


@dataclass(frozen=True)
class ColorSpec:
    """One colour of the exchange file.

    Attributes
    ----------
    name
        Display name.
    role
        ``design`` (from the designer), ``match`` (a library paint), ``measured`` or ``prediction``.
    gloss_gu
        60° gloss in GU.
    sets
        Measurement sets (3 or 5 angles each), Lab D65 / 10° at 45° illumination.
    paint_type, code, synthetic
        Optional paint type, library code, and whether the colour is synthetic (demo library).
    """

    name: str
    role: str
    gloss_gu: float
    sets: tuple[AspecularMeasurements, ...]
    paint_type: str | None = None
    code: str | None = None
    synthetic: bool = False

    def lab(self, angles_deg: tuple[float, ...]) -> np.ndarray:
        """Lab of the set with exactly *angles_deg*, shape (n, 3)."""
        for s in self.sets:
            if s.angles_deg == tuple(float(a) for a in angles_deg):
                return np.asarray(s.lab)
        raise XMLFormatError("measurementSet", f"a set at {angles_deg}", [s.angles_deg for s in self.sets])


def spec_from_design(
    design: FaceFlopTravelGloss,
    name: str | None = None,
    role: str = "design",
    five_angles: bool = False,
    paint_type: str | None = None,
) -> ColorSpec:
    """Evaluate a design at both 3-angle sets (and the 5-angle set if asked) for export (thesis §3.3.3)."""
    angle_sets = [ANGLES_3, ANGLES_3_ALT] + ([ANGLES_5] if five_angles else [])
    sets = tuple(AspecularMeasurements.from_design(design, a) for a in angle_sets)
    kind = paint_type or ("solid" if design.is_solid else "metallic")
    return ColorSpec(name or design.name or "design", role, float(design.gloss_gu), sets, kind)


def spec_from_lab(
    name: str,
    lab_by_angle: dict[float, tuple[float, float, float]],
    gloss_gu: float,
    role: str = "match",
    paint_type: str | None = None,
    code: str | None = None,
    synthetic: bool = False,
    five_angles: bool = False,
) -> ColorSpec:
    """Build a spec from Lab per angle (e.g. a library paint); every standard set present is exported."""
    angle_sets = [ANGLES_3, ANGLES_3_ALT] + ([ANGLES_5] if five_angles else [])
    sets = []
    for angles in angle_sets:
        if all(a in lab_by_angle for a in angles):
            sets.append(AspecularMeasurements(angles, np.array([lab_by_angle[a] for a in angles]), gloss_gu))
    if not sets:
        raise XMLFormatError("lab_by_angle", "Lab at 15/45/110 or 25/45/75", sorted(lab_by_angle))
    return ColorSpec(name, role, float(gloss_gu), tuple(sets), paint_type, code, synthetic)


def _fmt(v: float) -> str:
    return f"{v:.{DECIMALS}f}"


def _angle(a: float) -> str:
    return str(int(a)) if float(a).is_integer() else repr(float(a))


def colors_to_xml(specs: list[ColorSpec] | tuple[ColorSpec, ...]) -> bytes:
    """Serialise colours to the thesis XML (UTF-8 bytes, 2-space indent)."""
    if not specs:
        raise XMLFormatError("colors", "at least one colour", 0)
    ET.register_namespace("", NAMESPACE)
    root = ET.Element(f"{_NS}colors", {"version": "1"})
    for spec in specs:
        if spec.role not in ROLES:
            raise XMLFormatError("role", " | ".join(ROLES), spec.role)
        attrs = {"name": spec.name, "role": spec.role}
        if spec.paint_type:
            attrs["type"] = spec.paint_type
        if spec.code:
            attrs["code"] = spec.code
        if spec.synthetic:
            attrs["synthetic"] = "true"
        color = ET.SubElement(root, f"{_NS}color", attrs)
        ET.SubElement(
            color,
            f"{_NS}conditions",
            {"illuminant": "D65", "observer": OBSERVER, "illuminationAngleDeg": "45"},
        )
        gloss = ET.SubElement(color, f"{_NS}gloss", {"geometryDeg": "60", "unit": "GU"})
        gloss.text = _fmt(spec.gloss_gu)
        for s in spec.sets:
            ms = ET.SubElement(
                color, f"{_NS}measurementSet", {"angles": " ".join(_angle(a) for a in s.angles_deg)}
            )
            for a, (L, A, B) in zip(s.angles_deg, np.asarray(s.lab), strict=True):
                ET.SubElement(
                    ms, f"{_NS}lab", {"aspecularDeg": _angle(a), "L": _fmt(L), "a": _fmt(A), "b": _fmt(B)}
                )
    ET.indent(root, "  ")
    return ET.tostring(root, encoding="UTF-8", xml_declaration=True) + b"\n"


def write_color_xml(specs: list[ColorSpec] | tuple[ColorSpec, ...], path: str | Path) -> Path:
    """Write :func:`colors_to_xml` to *path*; returns the path."""
    path = Path(path)
    path.write_bytes(colors_to_xml(specs))
    return path


def _num(elem: ET.Element, attr: str, where: str, lo: float, hi: float, text: str | None = None) -> float:
    raw = elem.get(attr) if text is None else text
    if raw is None:
        raise XMLFormatError(f"{where}@{attr}", "a required attribute", None)
    try:
        v = float(raw)
    except ValueError as exc:
        raise XMLFormatError(f"{where}@{attr}", f"a number in [{lo:g}, {hi:g}]", raw) from exc
    if not math.isfinite(v) or not lo <= v <= hi:
        raise XMLFormatError(f"{where}@{attr}", f"a number in [{lo:g}, {hi:g}]", raw)
    return v


def read_color_xml(source: str | Path | bytes) -> list[ColorSpec]:
    """Read the thesis XML (hostile or malformed files raise :class:`XMLFormatError` subclasses)."""
    root = parse_xml(source, MAX_XML_BYTES)
    if root.tag != f"{_NS}colors":
        raise XMLFormatError("root", f"<colors> in namespace {NAMESPACE}", root.tag)
    if root.get("version") != "1":
        raise XMLFormatError("colors@version", '"1"', root.get("version"))
    specs: list[ColorSpec] = []
    colors = list(root)
    if not colors:
        raise XMLFormatError("colors", "at least one <color>", 0)
    for i, color in enumerate(colors):
        where = f"color[{i}]"
        if color.tag != f"{_NS}color":
            raise XMLFormatError(where, "<color>", color.tag)
        role = color.get("role")
        if role not in ROLES:
            raise XMLFormatError(f"{where}@role", " | ".join(ROLES), role)
        kind = color.get("type")
        if kind is not None and kind not in PAINT_TYPES:
            raise XMLFormatError(f"{where}@type", " | ".join(PAINT_TYPES), kind)
        name = color.get("name")
        if not name:
            raise XMLFormatError(f"{where}@name", "a non-empty name", name)
        synthetic = color.get("synthetic", "false")
        if synthetic not in ("true", "false", "1", "0"):
            raise XMLFormatError(f"{where}@synthetic", "true | false", synthetic)
        cond = color.find(f"{_NS}conditions")
        if cond is None:
            raise XMLFormatError(f"{where}/conditions", "a <conditions> element", None)
        if cond.get("illuminant") != "D65" or cond.get("observer") != OBSERVER:
            raise XMLFormatError(
                f"{where}/conditions", f"illuminant D65, observer {OBSERVER}", dict(cond.attrib)
            )
        if cond.get("illuminationAngleDeg") not in ("45", "45.0"):
            raise XMLFormatError(
                f"{where}/conditions@illuminationAngleDeg", "45", cond.get("illuminationAngleDeg")
            )
        gloss_el = color.find(f"{_NS}gloss")
        if gloss_el is None:
            raise XMLFormatError(f"{where}/gloss", "one <gloss> element (60°, GU)", None)
        if gloss_el.get("geometryDeg") not in ("60", "60.0") or gloss_el.get("unit") != "GU":
            raise XMLFormatError(f"{where}/gloss", 'geometryDeg="60" unit="GU"', dict(gloss_el.attrib))
        gloss = _num(gloss_el, "value", f"{where}/gloss", 0.0, 100.0, text=(gloss_el.text or "").strip())
        sets = []
        for j, ms in enumerate(color.findall(f"{_NS}measurementSet")):
            swhere = f"{where}/measurementSet[{j}]"
            labs = ms.findall(f"{_NS}lab")
            if len(labs) not in (3, 5):
                raise XMLFormatError(swhere, "3 or 5 <lab> values", len(labs))
            angles = tuple(_num(e, "aspecularDeg", f"{swhere}/lab", -89.999, 179.999) for e in labs)
            declared = ms.get("angles", "").split()
            try:
                declared_f = tuple(float(a) for a in declared)
            except ValueError as exc:
                raise XMLFormatError(f"{swhere}@angles", "space-separated angles", ms.get("angles")) from exc
            if declared_f != angles:
                raise XMLFormatError(f"{swhere}@angles", f"the lab angles {angles}", ms.get("angles"))
            lab = np.array(
                [[_num(e, ch, f"{swhere}/lab", *LAB_RANGES[ch]) for ch in LAB_CHANNELS] for e in labs]
            )
            try:
                sets.append(AspecularMeasurements(angles, lab, gloss))
            except ValueError as exc:
                raise XMLFormatError(
                    swhere, "strictly increasing aspecular angles", angles, str(exc)
                ) from exc
        if not sets:
            raise XMLFormatError(f"{where}/measurementSet", "at least one set", 0)
        specs.append(
            ColorSpec(name, role, gloss, tuple(sets), kind, color.get("code"), synthetic in ("true", "1"))
        )
    return specs
