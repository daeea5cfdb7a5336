"""CxF3 (ISO 17972-1) import / export of multi-angle colours: libraries, and a design with its match.

Written by hand against the CxF3-core schema (namespace ``http://colorexchangeformat.com/CxF3-core``)
and read with defusedxml (:mod:`station.formulate.safe_xml`); colour-cxf parses what we write
(tests/formulate/test_xml_cxf.py checks that), but it parses with a non-hardened parser, so it is not
used on files from outside.

Layout: one ``ColorSpecification`` per aspecular angle (``Id="CS45as15"``: D65, 10_Degree,
E308_Table6, ``MultiAngle/BRDFAngle`` with IlluminationAngle 45 and the Aspecular angle, notation
``45as15``); one ``Object`` per paint whose ``ColorValues`` hold one ``ColorCIELab`` per angle, each
pointing at its specification. CxF3 has no gloss element: the 60° gloss, the paint type, the role
and the synthetic flag travel as ``Tag`` name/value pairs (``cacad.gloss_gu_60``, ``cacad.type``,
``cacad.role``, ``cacad.synthetic``, ``cacad.angle_sets``).

Stated precision: 4 decimals for Lab and gloss; import(export(x)) equals x rounded to 1e-4 and a
second export is byte-identical (tests).
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET  # building only; parsing goes through defusedxml
from pathlib import Path

import numpy as np

from station.formulate.color_xml import ColorSpec
from station.formulate.errors import XMLFormatError
from station.formulate.library import PAINT_TYPES, STANDARD_ANGLES, Library
from station.formulate.safe_xml import parse_xml
from station.model import AspecularMeasurements
from station.model.domain import ILLUMINATION_DEG, LAB_RANGES, aspecular_name, format_angle

NAMESPACE = "http://colorexchangeformat.com/CxF3-core"
MAX_CXF_BYTES = 64 << 20
DECIMALS = 4
_NS = f"{{{NAMESPACE}}}"
CREATOR = "CACAD Station"
#: Fixed so exports are byte-reproducible; CxF3 requires a CreationDate.
CREATION_DATE = "2009-01-01T00:00:00Z"

Record = tuple[str, dict[float, tuple[float, float, float]], dict[str, str]]


_angle = format_angle


def _sub(parent: ET.Element, tag: str, text: str | None = None, **attrs: str) -> ET.Element:
    e = ET.SubElement(parent, f"{_NS}{tag}", attrs)
    if text is not None:
        e.text = text
    return e


def records_to_cxf(records: list[Record], description: str) -> bytes:
    """Serialise (name, {angle: Lab}, tags) records to CxF3 bytes."""
    if not records:
        raise XMLFormatError("objects", "at least one colour", 0)
    ET.register_namespace("cc", NAMESPACE)
    root = ET.Element(f"{_NS}CxF")
    info = _sub(root, "FileInformation")
    _sub(info, "Creator", CREATOR)
    _sub(info, "CreationDate", CREATION_DATE)
    _sub(info, "Description", description)
    res = _sub(root, "Resources")
    objs = _sub(res, "ObjectCollection")
    angles = sorted({a for _, lab, _ in records for a in lab})
    fmt = f"{{:.{DECIMALS}f}}"
    for i, (name, lab, tags) in enumerate(records):
        obj = _sub(objs, "Object", ObjectType="Standard", Name=name, Id=f"o{i + 1}")
        _sub(obj, "CreationDate", CREATION_DATE)
        values = _sub(obj, "ColorValues")
        for a in sorted(lab):
            c = _sub(values, "ColorCIELab", ColorSpecification=f"CS{aspecular_name(a)}")
            for tag, v in zip(("L", "A", "B"), lab[a], strict=True):
                _sub(c, tag, fmt.format(v))
        if tags:
            tc = _sub(obj, "TagCollection")
            for key in sorted(tags):
                _sub(tc, "Tag", Name=key, Value=tags[key])
    specs = _sub(res, "ColorSpecificationCollection")
    for a in angles:
        cs = _sub(specs, "ColorSpecification", Id=f"CS{aspecular_name(a)}")
        ts = _sub(cs, "TristimulusSpec")
        _sub(ts, "Illuminant", "D65")
        _sub(ts, "Observer", "10_Degree")
        _sub(ts, "Method", "E308_Table6")
        ms = _sub(cs, "MeasurementSpec")
        _sub(ms, "MeasurementType", "Colorimetric_Reflectance")
        gc = _sub(ms, "GeometryChoice")
        ma = _sub(gc, "MultiAngle")
        ba = _sub(ma, "BRDFAngle", Notation=aspecular_name(a))
        _sub(ba, "IlluminationAngle", "45")
        _sub(ba, "Aspecular", _angle(a))
    ET.indent(root, "  ")
    return ET.tostring(root, encoding="UTF-8", xml_declaration=True) + b"\n"


def _float(text: str | None, where: str, lo: float, hi: float) -> float:
    try:
        v = float((text or "").strip())
    except ValueError as exc:
        raise XMLFormatError(where, f"a number in [{lo:g}, {hi:g}]", text) from exc
    if not math.isfinite(v) or not lo <= v <= hi:
        raise XMLFormatError(where, f"a number in [{lo:g}, {hi:g}]", text)
    return v


def read_cxf_records(source: str | Path | bytes) -> list[Record]:
    """Parse CxF3 into (name, {aspecular angle: Lab}, tags) records (multi-angle Lab only)."""
    root = parse_xml(source, MAX_CXF_BYTES)
    if root.tag != f"{_NS}CxF":
        raise XMLFormatError("root", f"<CxF> in namespace {NAMESPACE}", root.tag)
    angle_of: dict[str, float] = {}
    for cs in root.iter(f"{_NS}ColorSpecification"):
        cid = cs.get("Id")
        ts = cs.find(f"{_NS}TristimulusSpec")
        if ts is not None:
            ill = (ts.findtext(f"{_NS}Illuminant") or "").strip()
            obs = (ts.findtext(f"{_NS}Observer") or "").strip()
            if ill != "D65" or obs != "10_Degree":
                raise XMLFormatError(f"ColorSpecification[{cid}]", "D65 and 10_Degree", (ill, obs))
        ba = cs.find(f".//{_NS}MultiAngle/{_NS}BRDFAngle")
        if ba is None or cid is None:
            continue
        ill_angle = _float(ba.findtext(f"{_NS}IlluminationAngle"), f"{cid}/IlluminationAngle", -90, 90)
        if ill_angle != ILLUMINATION_DEG:
            raise XMLFormatError(f"{cid}/IlluminationAngle", f"{ILLUMINATION_DEG:g}", ill_angle)
        angle_of[cid] = _float(ba.findtext(f"{_NS}Aspecular"), f"{cid}/Aspecular", -89.999, 179.999)
    if not angle_of:
        raise XMLFormatError("ColorSpecificationCollection", "multi-angle (BRDFAngle) specifications", 0)
    records: list[Record] = []
    for obj in root.iter(f"{_NS}Object"):
        name = obj.get("Name") or obj.get("Id") or ""
        if not name:
            raise XMLFormatError("Object@Name", "a non-empty name", None)
        lab: dict[float, tuple[float, float, float]] = {}
        for c in obj.iter(f"{_NS}ColorCIELab"):
            ref = c.get("ColorSpecification", "")
            if ref not in angle_of:
                raise XMLFormatError(f"Object[{name}]/ColorCIELab", "a multi-angle ColorSpecification", ref)
            where = f"Object[{name}]@{angle_of[ref]:g}"
            trip = (
                _float(c.findtext(f"{_NS}L"), f"{where}/L", *LAB_RANGES["L"]),
                _float(c.findtext(f"{_NS}A"), f"{where}/A", *LAB_RANGES["a"]),
                _float(c.findtext(f"{_NS}B"), f"{where}/B", *LAB_RANGES["b"]),
            )
            if angle_of[ref] in lab:
                raise XMLFormatError(where, "one Lab per angle", angle_of[ref])
            lab[angle_of[ref]] = trip
        tags = {t.get("Name", ""): t.get("Value", "") for t in obj.iter(f"{_NS}Tag")}
        records.append((name, lab, tags))
    if not records:
        raise XMLFormatError("ObjectCollection", "at least one Object", 0)
    return records


# -- libraries ---------------------------------------------------------------------------------------
def library_to_cxf(library: Library) -> bytes:
    """CxF3 of a whole library (every angle it holds); synthetic libraries say so in the description."""
    fmt = f"{{:.{DECIMALS}f}}"
    recs: list[Record] = []
    for i in range(len(library)):
        lab = {
            angle: (float(L), float(a), float(b))
            for angle, (L, a, b) in zip(library.angles_deg, library.lab[i], strict=True)
        }
        tags = {"cacad.type": str(library.types[i]), "cacad.gloss_gu_60": fmt.format(library.gloss_gu[i])}
        if library.synthetic:
            tags["cacad.synthetic"] = "true"
        recs.append((str(library.codes[i]), lab, tags))
    return records_to_cxf(recs, library.name)


def write_library_cxf(library: Library, path: str | Path) -> Path:
    """Write :func:`library_to_cxf` to *path*."""
    path = Path(path)
    path.write_bytes(library_to_cxf(library))
    return path


def read_library_cxf(source: str | Path | bytes, name: str | None = None) -> Library:
    """Read a CxF3 library: every object needs Lab at 15/45/110 and the same angle set as the others."""
    recs = read_cxf_records(source)
    description = (
        parse_xml(source, MAX_CXF_BYTES).findtext(f"{_NS}FileInformation/{_NS}Description") or ""
    ).strip()
    angles0 = sorted(recs[0][1])
    order = list(STANDARD_ANGLES) + [a for a in angles0 if a not in STANDARD_ANGLES]
    codes, types, gloss, labs = [], [], [], []
    for rname, lab, tags in recs:
        if sorted(lab) != angles0:
            raise XMLFormatError(f"Object[{rname}]", f"Lab at the angles {angles0}", sorted(lab))
        if not all(a in lab for a in STANDARD_ANGLES):
            raise XMLFormatError(f"Object[{rname}]", "Lab at 15, 45 and 110 degrees", sorted(lab))
        kind = tags.get("cacad.type", "solid")
        if kind not in PAINT_TYPES:
            raise XMLFormatError(f"Object[{rname}]/Tag cacad.type", " | ".join(PAINT_TYPES), kind)
        codes.append(rname)
        types.append(kind)
        gloss.append(_float(tags.get("cacad.gloss_gu_60", "90"), f"Object[{rname}]/gloss", 0, 100))
        labs.append([lab[a] for a in order])
    if len(set(codes)) != len(codes):
        raise XMLFormatError("Object@Name", "unique names", len(codes) - len(set(codes)))
    synthetic = all(tags.get("cacad.synthetic") == "true" for _, _, tags in recs)
    return Library(
        name=name or description or ("cxf library (SYNTHETIC)" if synthetic else "cxf library"),
        codes=np.asarray(codes),
        types=np.asarray(types),
        gloss_gu=np.asarray(gloss),
        angles_deg=tuple(order),
        lab=np.asarray(labs),
        synthetic=synthetic,
        source="cxf3",
    )


# -- design and match --------------------------------------------------------------------------------
def specs_to_cxf(specs: list[ColorSpec] | tuple[ColorSpec, ...]) -> bytes:
    """CxF3 of colour specs (e.g. a design and its ColorSnap match); the set structure is kept in a tag."""
    fmt = f"{{:.{DECIMALS}f}}"
    recs: list[Record] = []
    for spec in specs:
        lab: dict[float, tuple[float, float, float]] = {}
        for s in spec.sets:
            for a, row in zip(s.angles_deg, np.asarray(s.lab), strict=True):
                lab[a] = (float(row[0]), float(row[1]), float(row[2]))
        tags = {
            "cacad.role": spec.role,
            "cacad.gloss_gu_60": fmt.format(spec.gloss_gu),
            "cacad.angle_sets": ";".join(" ".join(_angle(a) for a in s.angles_deg) for s in spec.sets),
        }
        if spec.paint_type:
            tags["cacad.type"] = spec.paint_type
        if spec.code:
            tags["cacad.code"] = spec.code
        if spec.synthetic:
            tags["cacad.synthetic"] = "true"
        recs.append((spec.name, lab, tags))
    return records_to_cxf(recs, "CACAD Station design export")


def read_cxf_specs(source: str | Path | bytes) -> list[ColorSpec]:
    """Read colour specs written by :func:`specs_to_cxf` (or any multi-angle CxF3 with 3/5-angle sets)."""
    out = []
    for name, lab, tags in read_cxf_records(source):
        gloss = _float(tags.get("cacad.gloss_gu_60", "90"), f"Object[{name}]/gloss", 0, 100)
        layout = tags.get("cacad.angle_sets") or " ".join(_angle(a) for a in sorted(lab))
        sets = []
        for part in layout.split(";"):
            try:
                angles = tuple(float(a) for a in part.split())
            except ValueError as exc:
                raise XMLFormatError(f"Object[{name}]/Tag cacad.angle_sets", "angle lists", part) from exc
            if any(a not in lab for a in angles):
                raise XMLFormatError(f"Object[{name}]", f"Lab at {angles}", sorted(lab))
            try:
                sets.append(AspecularMeasurements(angles, np.array([lab[a] for a in angles]), gloss))
            except ValueError as exc:
                raise XMLFormatError(f"Object[{name}]", "a valid angle set", angles, str(exc)) from exc
        kind = tags.get("cacad.type")
        if kind is not None and kind not in PAINT_TYPES:
            raise XMLFormatError(f"Object[{name}]/Tag cacad.type", " | ".join(PAINT_TYPES), kind)
        out.append(
            ColorSpec(
                name,
                tags.get("cacad.role", "measured"),
                gloss,
                tuple(sets),
                kind,
                tags.get("cacad.code"),
                tags.get("cacad.synthetic") == "true",
            )
        )
    return out
