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
``cacad.role``, ``cacad.synthetic``, ``cacad.angle_sets``) in a ``TagCollection Name="cacad"``.

Spectra and recipes (optional, per object, :class:`ObjectExtras`): reflectance factors per geometry as
``ColorValues/ReflectanceSpectrum`` (400–700 nm at 10 nm, :data:`station.model.spectra.WAVELENGTHS`)
pointing at a spectral ``ColorSpecification`` (``Id="SP45as15"``, ``Spectrum_Reflectance``, the same
``MultiAngle`` geometry, ``WavelengthRange StartWL="400" Increment="10"``), and the recipe as
``DeviceColorValues/ColorRecipe`` (colour-cxf's ``ColorRecipe``: ``Units`` g or fraction, its own
``CreationDate`` (the schema requires it), one
``Colorant`` per component with its ``Value``; the binder carries ``isBase="true"``).

``FileInformation/CreationDate`` and each object's ``CreationDate`` are the time of the export (UTC, to
the second) unless the caller passes *created* (for reproducible files).

Stated precision: 4 decimals for Lab and gloss, 6 for reflectance and recipe amounts; import(export(x))
equals x rounded so, and a second export with the same *created* is byte-identical (tests).
"""

from __future__ import annotations

import datetime as dt
import math
import xml.etree.ElementTree as ET  # building only; parsing goes through defusedxml
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from station.formulate.color_xml import ColorSpec
from station.formulate.errors import XMLFormatError
from station.formulate.library import PAINT_TYPES, STANDARD_ANGLES, Library
from station.formulate.safe_xml import parse_xml
from station.model import AspecularMeasurements
from station.model.cxf_names import CREATOR, NAMESPACE
from station.model.domain import ILLUMINATION_DEG, LAB_RANGES, aspecular_name, format_angle
from station.model.spectra import WAVELENGTHS

MAX_CXF_BYTES = 64 << 20
DECIMALS = 4
_NS = f"{{{NAMESPACE}}}"
SPECTRUM_DECIMALS = 6
RECIPE_UNITS = ("g", "fraction")

Record = tuple[str, dict[float, tuple[float, float, float]], dict[str, str]]


@dataclass(frozen=True)
class ObjectExtras:
    """What an object carries besides Lab: reflectance per geometry and a recipe.

    Attributes
    ----------
    spectra
        ``((aspecular angle °, (R at 400, 410, …, 700 nm)), …)``, reflectance factors ≥ 0 (a flake
        paint's radiance factor may exceed 1 near the specular).
    recipe
        ``((component, amount), …)`` in *recipe_units*; the component named *binder* is the base.
    recipe_units
        ``"g"`` (mass per batch) or ``"fraction"`` (mass fraction 0–1).
    binder
        Name of the base / binder component, or ``None``.
    """

    spectra: tuple[tuple[float, tuple[float, ...]], ...] = ()
    recipe: tuple[tuple[str, float], ...] = ()
    recipe_units: str = "g"
    binder: str | None = None

    def __post_init__(self) -> None:
        if self.recipe_units not in RECIPE_UNITS:
            raise XMLFormatError("ColorRecipe@Units", " | ".join(RECIPE_UNITS), self.recipe_units)
        n = WAVELENGTHS.size
        for angle, values in self.spectra:
            if len(values) != n or not all(math.isfinite(v) and v >= 0 for v in values):
                raise XMLFormatError(
                    f"ReflectanceSpectrum[{aspecular_name(angle)}]",
                    f"{n} finite values ≥ 0 (400–700 nm)",
                    len(values),
                )
        for name, amount in self.recipe:
            if not name or not math.isfinite(amount) or amount < 0:
                raise XMLFormatError(f"Colorant[{name}]", "a named component with an amount ≥ 0", amount)

    @property
    def empty(self) -> bool:
        """True when there is nothing to write."""
        return not self.spectra and not self.recipe


def creation_date(created: dt.datetime | None = None) -> str:
    """ISO 8601 UTC time stamp of *created* (default: now), to the second, as CxF3 writes it."""
    when = created or dt.datetime.now(dt.UTC)
    if when.tzinfo is None:
        raise XMLFormatError("CreationDate", "a time with a time zone", when.isoformat())
    return when.astimezone(dt.UTC).strftime("%Y-%m-%dT%H:%M:%SZ")


_angle = format_angle


def _sub(parent: ET.Element, tag: str, text: str | None = None, **attrs: str) -> ET.Element:
    e = ET.SubElement(parent, f"{_NS}{tag}", attrs)
    if text is not None:
        e.text = text
    return e


TAG_COLLECTION = "cacad"
"""``Name`` of the object's ``TagCollection`` (the schema requires one) holding the ``cacad.*`` tags."""


def records_to_cxf(
    records: list[Record],
    description: str,
    extras: Sequence[ObjectExtras | None] | None = None,
    created: dt.datetime | None = None,
) -> bytes:
    """Serialise (name, {angle: Lab}, tags) records to CxF3 bytes, with each record's optional
    :class:`ObjectExtras` (spectra, recipe) and the creation time *created* (default: now, UTC).

    The document validates against the published CxF3 core schema (3.0.018; tests check it).
    """
    if not records:
        raise XMLFormatError("objects", "at least one colour", 0)
    extras = list(extras) if extras is not None else [None] * len(records)
    if len(extras) != len(records):
        raise XMLFormatError("extras", f"one entry per record ({len(records)})", len(extras))
    stamp = creation_date(created)
    ET.register_namespace("cc", NAMESPACE)
    root = ET.Element(f"{_NS}CxF")
    info = _sub(root, "FileInformation")
    _sub(info, "Creator", CREATOR)
    _sub(info, "CreationDate", stamp)
    _sub(info, "Description", description)
    res = _sub(root, "Resources")
    objs = _sub(res, "ObjectCollection")
    for i, (record, extra) in enumerate(zip(records, extras, strict=True)):
        _write_object(objs, i, record, extra, stamp)
    specs = _sub(res, "ColorSpecificationCollection")
    for a in sorted({a for _, lab, _ in records for a in lab}):
        cs = _sub(specs, "ColorSpecification", Id=f"CS{aspecular_name(a)}")
        ts = _sub(cs, "TristimulusSpec")
        _sub(ts, "Illuminant", "D65")
        _sub(ts, "Observer", "10_Degree")
        _sub(ts, "Method", "E308_Table6")
        _write_geometry(cs, a, "Colorimetric_Reflectance")
    step = float(WAVELENGTHS[1] - WAVELENGTHS[0])
    for a in sorted({a for x in extras if x is not None for a, _ in x.spectra}):
        cs = _sub(specs, "ColorSpecification", Id=f"SP{aspecular_name(a)}")
        ms = _write_geometry(cs, a, "Spectrum_Reflectance")
        _sub(ms, "WavelengthRange", StartWL=format_angle(float(WAVELENGTHS[0])), Increment=format_angle(step))
    ET.indent(root, "  ")
    return ET.tostring(root, encoding="UTF-8", xml_declaration=True) + b"\n"


def _write_geometry(cs: ET.Element, angle: float, kind: str) -> ET.Element:
    """The ``MeasurementSpec`` of *cs*: *kind* and one ``MultiAngle/BRDFAngle`` at *angle* (°)."""
    ms = _sub(cs, "MeasurementSpec")
    _sub(ms, "MeasurementType", kind)
    gc = _sub(ms, "GeometryChoice")
    ma = _sub(gc, "MultiAngle")
    ba = _sub(ma, "BRDFAngle", Notation=aspecular_name(angle))
    _sub(ba, "IlluminationAngle", format_angle(ILLUMINATION_DEG))
    _sub(ba, "Aspecular", _angle(angle))
    return ms


def _write_object(objs: ET.Element, i: int, record: Record, extra: ObjectExtras | None, stamp: str) -> None:
    """One ``Object``: Lab per angle (4 decimals), then spectra and recipe (6 decimals), then tags.

    Schema order: ``CreationDate``, ``ColorValues``, ``DeviceColorValues``, ``TagCollection``; a
    ``ColorRecipe`` opens with its own ``CreationDate``; a ``TagCollection`` needs a ``Name``.
    """
    name, lab, tags = record
    fmt = f"{{:.{DECIMALS}f}}"
    sfmt = f"{{:.{SPECTRUM_DECIMALS}f}}"
    obj = _sub(objs, "Object", ObjectType="Standard", Name=name, Id=f"o{i + 1}")
    _sub(obj, "CreationDate", stamp)
    values = _sub(obj, "ColorValues")
    for a in sorted(lab):
        c = _sub(values, "ColorCIELab", ColorSpecification=f"CS{aspecular_name(a)}")
        for tag, v in zip(("L", "A", "B"), lab[a], strict=True):
            _sub(c, tag, fmt.format(v))
    if extra is not None:
        for a, refl in sorted(extra.spectra):
            _sub(
                values,
                "ReflectanceSpectrum",
                " ".join(sfmt.format(v) for v in refl),
                ColorSpecification=f"SP{aspecular_name(a)}",
                StartWL=format_angle(float(WAVELENGTHS[0])),
            )
        if extra.recipe:
            device = _sub(obj, "DeviceColorValues")
            recipe = _sub(device, "ColorRecipe", Units=extra.recipe_units, Name=name)
            _sub(recipe, "CreationDate", stamp)
            for component, amount in extra.recipe:
                attrs = {"Name": component}
                if component == extra.binder:
                    attrs["isBase"] = "true"
                col = _sub(recipe, "Colorant", **attrs)
                _sub(col, "Value", sfmt.format(amount))
    if tags:
        tc = _sub(obj, "TagCollection", Name=TAG_COLLECTION)
        for key in sorted(tags):
            _sub(tc, "Tag", Name=key, Value=tags[key])


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
    return read_cxf_objects(source)[0]


def _read_extras(obj: ET.Element, name: str, angle_of: dict[str, float]) -> ObjectExtras | None:
    """Spectra per geometry and the recipe of one ``Object``, or ``None`` when it has neither."""
    spectra: list[tuple[float, tuple[float, ...]]] = []
    n = WAVELENGTHS.size
    for sp in obj.iter(f"{_NS}ReflectanceSpectrum"):
        ref = sp.get("ColorSpecification", "")
        if ref not in angle_of:
            raise XMLFormatError(
                f"Object[{name}]/ReflectanceSpectrum", "a multi-angle ColorSpecification", ref
            )
        start = _float(sp.get("StartWL"), f"Object[{name}]/ReflectanceSpectrum@StartWL", 0, 10000)
        if start != float(WAVELENGTHS[0]):
            raise XMLFormatError(f"Object[{name}]/ReflectanceSpectrum@StartWL", f"{WAVELENGTHS[0]:g}", start)
        where = f"Object[{name}]/ReflectanceSpectrum[{ref}]"
        parts = (sp.text or "").split()
        if len(parts) != n:
            raise XMLFormatError(where, f"{n} values (400–700 nm at 10 nm)", len(parts))
        spectra.append((angle_of[ref], tuple(_float(v, where, 0, 1000) for v in parts)))
    if len({a for a, _ in spectra}) != len(spectra):
        raise XMLFormatError(f"Object[{name}]/ReflectanceSpectrum", "one spectrum per geometry", len(spectra))
    recipe: list[tuple[str, float]] = []
    units, binder = "g", None
    rec = obj.find(f"{_NS}DeviceColorValues/{_NS}ColorRecipe")
    if rec is not None:
        units = rec.get("Units", "g")
        if units not in RECIPE_UNITS:
            raise XMLFormatError(f"Object[{name}]/ColorRecipe@Units", " | ".join(RECIPE_UNITS), units)
        for col in rec.iter(f"{_NS}Colorant"):
            cname = col.get("Name", "")
            where = f"Object[{name}]/Colorant[{cname}]"
            if not cname:
                raise XMLFormatError(f"Object[{name}]/Colorant@Name", "a non-empty name", None)
            recipe.append((cname, _float(col.findtext(f"{_NS}Value"), where, 0, 1e9)))
            if col.get("isBase") == "true":
                binder = cname
    if not spectra and not recipe:
        return None
    return ObjectExtras(tuple(sorted(spectra)), tuple(recipe), units, binder)


def read_cxf_objects(source: str | Path | bytes) -> tuple[list[Record], list[ObjectExtras | None]]:
    """Parse CxF3 into records and each record's :class:`ObjectExtras` (``None`` where it has none)."""
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
    extras: list[ObjectExtras | None] = []
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
        extras.append(_read_extras(obj, name, angle_of))
    if not records:
        raise XMLFormatError("ObjectCollection", "at least one Object", 0)
    return records, extras


# -- libraries ---------------------------------------------------------------------------------------
def library_extras(library: Library, spectra: bool = False) -> list[ObjectExtras | None]:
    """Each paint's recipe (mass fractions) and, with *spectra*, its predicted reflectance per library
    angle from the colorant model (:func:`station.formulate.colorants.predict_reflectance`); ``None``
    for a library without recipes."""
    if library.recipes is None or library.colorant_names is None:
        return [None] * len(library)
    names = library.colorant_names
    refl = None
    if spectra:
        from station.formulate.colorants import default_database, predict_reflectance

        db = default_database()
        if set(names) <= set(db.names):
            conc = np.zeros((len(library), len(db.names)))
            for j, n in enumerate(names):
                conc[:, db.names.index(n)] = library.recipes[:, j]
            refl = predict_reflectance(conc, library.angles_deg, db)
    out: list[ObjectExtras | None] = []
    for i in range(len(library)):
        rec = tuple((n, float(v)) for n, v in zip(names, library.recipes[i], strict=True) if v > 0)
        sp = (
            ()
            if refl is None
            else tuple((a, tuple(float(v) for v in refl[i, j])) for j, a in enumerate(library.angles_deg))
        )
        out.append(ObjectExtras(sp, rec, "fraction"))
    return out


def library_to_cxf(library: Library, *, spectra: bool = False, created: dt.datetime | None = None) -> bytes:
    """CxF3 of a whole library (every angle it holds, recipes where it has them, predicted spectra with
    *spectra*); synthetic libraries say so in a tag on every paint."""
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
    return records_to_cxf(recs, library.name, library_extras(library, spectra), created)


def write_library_cxf(
    library: Library, path: str | Path, *, spectra: bool = False, created: dt.datetime | None = None
) -> Path:
    """Write :func:`library_to_cxf` to *path*."""
    path = Path(path)
    path.write_bytes(library_to_cxf(library, spectra=spectra, created=created))
    return path


def read_library_cxf(source: str | Path | bytes, name: str | None = None) -> Library:
    """Read a CxF3 library: every object needs Lab at 15/45/110 and the same angle set as the others."""
    recs, extras = read_cxf_objects(source)
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
    recipes, colorant_names = _recipe_matrix(extras)
    return Library(
        name=name or description or ("cxf library (SYNTHETIC)" if synthetic else "cxf library"),
        codes=np.asarray(codes),
        types=np.asarray(types),
        gloss_gu=np.asarray(gloss),
        angles_deg=tuple(order),
        lab=np.asarray(labs),
        synthetic=synthetic,
        recipes=recipes,
        colorant_names=colorant_names,
        source="cxf3",
    )


def _recipe_matrix(extras: list[ObjectExtras | None]) -> tuple[np.ndarray | None, tuple[str, ...] | None]:
    """(N, C) mass fractions of the objects' fraction recipes (library CSV's rule for column order)."""
    from station.formulate.library_csv import recipe_matrix

    recipes = []
    for x in extras:
        if x is not None and x.recipe and x.recipe_units != "fraction":
            raise XMLFormatError(
                "ColorRecipe@Units", "fraction (a library holds mass fractions)", x.recipe_units
            )
        recipes.append({} if x is None else dict(x.recipe))
    return recipe_matrix(recipes)


# -- design and match --------------------------------------------------------------------------------
def specs_to_cxf(
    specs: list[ColorSpec] | tuple[ColorSpec, ...],
    extras: Sequence[ObjectExtras | None] | None = None,
    created: dt.datetime | None = None,
) -> bytes:
    """CxF3 of colour specs (e.g. a design, its ColorSnap match and the formulated recipe with its
    predicted spectra in *extras*); the set structure is kept in a tag."""
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
    return records_to_cxf(recs, "CACAD Station design export", extras, created)


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
