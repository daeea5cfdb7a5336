"""CxF3 (ISO 17972-1) multi-angle measurements through ``colour-cxf``: read and write.

Layout written (and read): one ``ColorSpecification`` per geometry (``Id="CS45as15"``) whose
``MeasurementSpec`` has a ``GeometryChoice/MultiAngle`` with one ``BRDFAngle`` (IlluminationAngle,
Aspecular, Notation ``45as15``), the ``WavelengthRange`` of the spectra and the ``Device``
(manufacturer, model, serial); its ``TristimulusSpec`` gives the illuminant and observer of the Lab.

Also read: one ``ColorSpecification`` whose ``MultiAngle`` lists several ``BRDFAngle`` (the layout of
colour-cxf's test resources). A value pointing at it names its geometry by ``Name`` equal to a
``BRDFAngle/@Notation``; unnamed values of one kind take the angles in ``BRDFAngle`` order and must
then number exactly one per ``BRDFAngle``. An out-of-plane ``Azimuth`` other than 0 is refused (the
product's geometries are in-plane). A ``SingleAngle`` specification (e.g. 45/0, annular or
uniplanar) is one geometry, ``<IlluminationAngle>as<IlluminationAngle − MeasurementAngle>``
(45/0 → ``45as45``); 0/45 is refused (illumination along the normal has no aspecular side).
Values under other geometries (sphere, emissive, unknown) are skipped.

One ``Object`` per sample (its
``Name``; ``CreationDate`` is the measurement instant) whose ``ColorValues`` hold a ``ColorCIELab``
and/or a ``ReflectanceSpectrum`` per geometry, each pointing at its specification. Vendor texture
values travel in a ``TagCollection Name="texture"``: ``Tag Name="VENDOR|NAME|GEOMETRY"`` (GEOMETRY
empty for a per-sample value) with the number as ``Value``. A measurement without an instant is
written with the schema's required ``CreationDate`` set to 2000-01-01 and a ``TagCollection
Name="measurement"`` holding ``Tag Name="measured_at" Value="unknown"``; the reader then gives no
instant, so the placeholder never passes for a date.

The bytes are screened first with defusedxml (no DTD, no entity declarations, no external
references: XXE and "billion laughs" are refused before any expansion), then parsed by colour-cxf.
Refusals are :class:`~station.ingest.errors.CxfImportError` naming the element and field.
"""

from __future__ import annotations

import datetime as dt
import itertools
import math
import warnings
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import colour_cxf
import defusedxml.ElementTree as DET
from colour_cxf import cxf3
from defusedxml import DefusedXmlException
from xsdata.exceptions import ConverterWarning, ParserError
from xsdata.models.datatype import XmlDateTime

from station.ingest.errors import CxfImportError
from station.ingest.formats._text import decode_utf8, factory, read_bytes
from station.ingest.formats.measurement import (
    ImportedFile,
    ImportedMeasurement,
    Instrument,
    VendorValue,
    build_measurement,
    canonical_geometry,
    observer_degrees,
    observer_name,
)
from station.model.cxf_names import CREATOR, NAMESPACE
from station.model.domain import format_angle, geometry_name

__all__ = ["is_complete", "read_cxf", "write_cxf"]

TEXTURE_TAGS = "texture"
#: ``TagCollection`` marking an object whose ``CreationDate`` (required by the schema) is a placeholder.
UNDATED_TAGS = "measurement"
_UNDATED = cxf3.TagCollection(tag=[cxf3.Tag(name="measured_at", value="unknown")], name=UNDATED_TAGS)
LAB_DECIMALS = 4
SPECTRA_DECIMALS = 6


def _screen(data: bytes, file: str) -> None:
    """Refuse hostile or malformed XML before colour-cxf (a non-hardened parser) sees it."""
    head = data.lower()
    if b"<!doctype" in head or b"<!entity" in head:
        raise CxfImportError(file, "prolog", "DOCTYPE", "XML without a DTD or entity declarations")
    try:
        root = DET.fromstring(data, forbid_dtd=True, forbid_entities=True, forbid_external=True)
    except DefusedXmlException as exc:
        raise CxfImportError(file, "prolog", "DOCTYPE", "XML without a DTD or entities", str(exc)) from exc
    except DET.ParseError as exc:
        line = getattr(exc, "position", (0, 0))[0]
        raise CxfImportError(
            file, f"line {line}", "xml", "well-formed XML (file truncated?)", str(exc)
        ) from exc
    if root.tag != f"{{{NAMESPACE}}}CxF":
        raise CxfImportError(file, "root", "CxF", f"a <CxF> root in namespace {NAMESPACE}", root.tag)


def _instant(value: Any) -> dt.datetime | None:
    if value is None:
        return None
    raw = getattr(value, "value", value)
    if isinstance(raw, XmlDateTime):
        out = raw.to_datetime()
    elif isinstance(raw, dt.datetime):
        out = raw
    else:
        try:
            out = dt.datetime.fromisoformat(str(raw).replace("Z", "+00:00"))
        except ValueError:
            return None
    return out if out.tzinfo is not None else out.replace(tzinfo=dt.UTC)


def _enum_text(value: Any) -> str:
    raw = getattr(value, "value", value)
    raw = getattr(raw, "value", raw)  # wrapper element → enum → text
    return "" if raw is None else str(raw)


def _angles(cs: Any, where: str, file: str) -> tuple[list[str], dict[str, str]] | tuple[str, str, str] | None:
    """Geometry names of a specification in ``BRDFAngle`` order and its Notation → name map; ``None``
    for a non-directional geometry; ``(field, accepted, got)`` when its geometry is outside the
    product's (refused when a value uses it)."""
    ms = cs.measurement_spec
    choice = ms.geometry_choice.choice if ms and ms.geometry_choice else None
    if isinstance(choice, cxf3.SingleAngleType):
        ill, meas = choice.illumination_angle, choice.measurement_angle
        if ill is None or meas is None or not (math.isfinite(ill) and math.isfinite(meas)):
            raise CxfImportError(file, f"{where}/SingleAngle", "MeasurementAngle", "finite angles (degrees)")
        if ill == 0.0:
            return (
                "IlluminationAngle",
                "a directional geometry such as 45/0",
                f"{where}/SingleAngle: 0/{meas:g}",
            )
        return [geometry_name(ill, ill - meas)], {}
    if not isinstance(choice, cxf3.MultiAngleType):
        return None
    if not choice.brdfangle:
        raise CxfImportError(file, f"{where}/MultiAngle", "BRDFAngle", "at least one BRDFAngle", 0)
    names: list[str] = []
    notations: dict[str, str] = {}
    for n, angle in enumerate(choice.brdfangle, start=1):
        here = f"{where}/BRDFAngle[{n}]"
        if angle.illumination_angle is None or angle.aspecular is None:
            raise CxfImportError(file, here, "Aspecular", "IlluminationAngle and Aspecular")
        if not (math.isfinite(angle.illumination_angle) and math.isfinite(angle.aspecular)):
            raise CxfImportError(file, here, "Aspecular", "finite angles (degrees)")
        if angle.azimuth not in (None, 0.0):
            return ("Azimuth", "an in-plane geometry (Azimuth 0)", f"{here}: Azimuth {angle.azimuth:g}°")
        g = geometry_name(angle.illumination_angle, angle.aspecular)
        if g in names:
            raise CxfImportError(file, here, "BRDFAngle", "each geometry once per MultiAngle", g)
        names.append(g)
        if angle.notation:
            notations[str(angle.notation).strip()] = g
    return names, notations


def _specs(doc: cxf3.CxF, file: str) -> dict[str, dict[str, Any]]:
    """Per ColorSpecification Id: geometry names (``None``: not directional; ``refused``: why not read),
    Notation map, illuminant, observer, wavelength start/step, device."""
    out: dict[str, dict[str, Any]] = {}
    coll = doc.resources.color_specification_collection if doc.resources else None
    for k, cs in enumerate(coll.color_specification if coll else []):
        where = f"ColorSpecification[{k + 1}]"  # an index, never the file's text
        angles = _angles(cs, where, file)
        if angles is None or len(angles) == 3:
            out[str(cs.id)] = {"geometries": None, "refused": angles, "where": where}
            continue
        ts = cs.tristimulus_spec
        ill = ts.illuminant_or_custom_illuminant if ts else None
        illuminant = (
            _enum_text(ill) if isinstance(ill, cxf3.Illuminant) else "D65" if ill is None else "custom"
        )
        obs_text = _enum_text(ts.observer) if ts and ts.observer else "10_Degree"
        ms = cs.measurement_spec
        wr = ms.wavelength_range if ms else None
        dev = ms.device if ms else None
        out[str(cs.id)] = {
            "geometries": angles[0],
            "notations": angles[1],
            "where": where,
            "illuminant": illuminant,
            "observer": observer_name(obs_text) or obs_text,
            "start": None if wr is None else wr.start_wl,
            "step": None if wr is None else wr.increment,
            "instrument": Instrument(
                model=(dev.model or "") if dev else "",
                serial=str(dev.serial_number or "") if dev else "",
                manufacturer=(dev.manufacturer or "") if dev else "",
            ),
        }
    return out


class _Declared(Exception):
    """A DTD or entity declaration: the reader refuses the document whole, no need to read on."""


def is_complete(data: bytes) -> bool:
    """Whether *data* holds a whole XML document: its root element is closed (a document a writer is
    still writing is not); malformed or declaring XML counts as complete: the reader refuses it."""
    from xml.parsers import expat

    parser = expat.ParserCreate()
    depth = 0
    closed = False

    def start(name: str, attrs: object) -> None:
        nonlocal depth
        depth += 1

    def end(name: str) -> None:
        nonlocal depth, closed
        depth -= 1
        closed = closed or depth == 0

    def declared(*args: object) -> None:
        raise _Declared

    parser.StartElementHandler = start
    parser.EndElementHandler = end
    parser.StartDoctypeDeclHandler = declared
    parser.EntityDeclHandler = declared
    try:
        parser.Parse(data, False)
    except (expat.ExpatError, _Declared):
        return True
    return closed


def _parse(data: bytes, file: str) -> cxf3.CxF:
    """The colour-cxf document of screened *data*; a value xsdata cannot convert is refused by element."""
    try:
        with warnings.catch_warnings():  # xsdata keeps a value it cannot convert, with a warning: refuse it
            warnings.simplefilter("error", ConverterWarning)
            return colour_cxf.read_cxf(data)
    except ConverterWarning as exc:
        element, _, rest = str(exc).partition("\n")
        fld = element.rsplit("`", 2)[-2] if element.count("`") >= 2 else "value"
        raise CxfImportError(
            file, f"element {fld.split('.')[0]}", fld, "a value of the element's type", rest.strip()
        ) from exc
    except (ParserError, ValueError, TypeError) as exc:
        raise CxfImportError(file, "document", "xml", "CxF3 elements with valid values", str(exc)) from exc


def read_cxf(path: Path | str, data: bytes | None = None) -> ImportedFile:
    """Read the multi-angle objects of a CxF3 file (module doc for the layouts and the refusals)."""
    path = Path(path)
    file = path.name
    data = read_bytes(path, CxfImportError, data)
    decode_utf8(data, file, CxfImportError)  # CxF3 files are UTF-8: refuse others by line, not by parser
    _screen(data, file)
    doc = _parse(data, file)
    specs = _specs(doc, file)
    coll = doc.resources.object_collection if doc.resources else None
    objects = coll.object_value if coll else []
    if not objects:
        raise CxfImportError(file, "Resources/ObjectCollection", "Object", "at least one Object")
    return ImportedFile("cxf", file, tuple(_object(obj, i, specs, file) for i, obj in enumerate(objects, 1)))


def _element(v: Any) -> str:
    """The CxF3 element name of a colour value (``ColorCIELab``, ``ReflectanceSpectrum``)."""
    return "ColorCIELab" if isinstance(v, cxf3.ColorCielab) else "ReflectanceSpectrum"


def _geometry_of(v: Any, spec: dict[str, Any], count: int, position: int, file: str, vwhere: str) -> str:
    """The geometry of value *v* under *spec*: by ``Name`` = a BRDFAngle Notation, else by its
    *position* among the *count* unnamed values of its kind pointing at the same specification."""
    names: list[str] = spec["geometries"]
    if len(names) == 1:
        return names[0]
    name = str(v.name or "").strip()
    if name in spec["notations"]:
        return str(spec["notations"][name])
    if count != len(names):
        raise CxfImportError(
            file,
            vwhere,
            "ColorSpecification",
            f"one {_element(v)} per BRDFAngle of {spec['where']} ({len(names)}, in BRDFAngle "
            "order) or a Name equal to a BRDFAngle Notation",
            count,
        )
    return names[position]


def _values(obj: Any, where: str, specs: dict[str, dict[str, Any]], file: str) -> list[tuple[str, dict]]:
    """The object's directional Lab and spectra grouped per geometry, in specification order."""
    values = obj.color_values.choice if obj.color_values else []
    kept = [
        (j, v) for j, v in enumerate(values, 1) if isinstance(v, (cxf3.ColorCielab, cxf3.ReflectanceSpectrum))
    ]
    unnamed: dict[tuple[str, type], list[int]] = {}
    for j, v in kept:
        spec = specs.get(str(v.color_specification))
        if spec is not None and spec["geometries"] and str(v.name or "").strip() not in spec["notations"]:
            unnamed.setdefault((str(v.color_specification), type(v)), []).append(j)
    per_geo: dict[str, dict[str, Any]] = {}
    for j, v in kept:
        kind = "lab" if isinstance(v, cxf3.ColorCielab) else "spectrum"
        vwhere = f"{where}/ColorValues[{j}] {_element(v)}"
        spec = specs.get(str(v.color_specification))
        if spec is None:
            raise CxfImportError(file, vwhere, "ColorSpecification", "the Id of a ColorSpecification", v.color_specification)  # fmt: skip
        if spec["geometries"] is None:
            if spec["refused"]:
                raise CxfImportError(file, vwhere, *spec["refused"])
            continue  # not a directional value (e.g. a sphere reading in the same file)
        group = unnamed.get((str(v.color_specification), type(v)), [])
        g = _geometry_of(v, spec, len(group), group.index(j) if j in group else 0, file, vwhere)
        slot = per_geo.setdefault(g, {"spec": spec, "err": factory(CxfImportError, file, vwhere)})
        if kind in slot:
            raise CxfImportError(file, vwhere, "geometry", f"one {_element(v)} per geometry", g)
        if isinstance(v, cxf3.ColorCielab):
            if v.l is None or v.a is None or v.b is None:
                raise CxfImportError(file, vwhere, "L", "L, A and B elements")
            slot["lab"] = (v.l, v.a, v.b)
        else:
            start = v.start_wl if v.start_wl is not None else spec["start"]
            if start is None or spec["step"] is None:
                raise CxfImportError(file, vwhere, "StartWL", "StartWL and a WavelengthRange Increment")
            slot["spectrum"] = list(v.value)
            slot["wl"] = [float(start + spec["step"] * n) for n in range(len(v.value))]
    first_seen: dict[str, int] = {}
    for slot in per_geo.values():
        first_seen.setdefault(slot["spec"]["where"], len(first_seen))
    # specifications in first-seen order; within one, its BRDFAngle order (named values may be shuffled)
    return sorted(
        per_geo.items(),
        key=lambda kv: (first_seen[kv[1]["spec"]["where"]], kv[1]["spec"]["geometries"].index(kv[0])),
    )


def _texture(obj: Any, where: str, file: str) -> list[VendorValue]:
    """The vendor texture values of the object's ``TagCollection Name="texture"``: each tag
    ``Name="VENDOR|NAME|GEOMETRY"`` (GEOMETRY empty: a per-sample value) with a finite ``Value``; the
    geometry is read in the domain's spelling, and one quantity holds one value per geometry."""
    texture: dict[tuple[str, str, str], VendorValue] = {}
    at = f"{where}/TagCollection"
    err = factory(CxfImportError, file, at)
    for tc in obj.tag_collection:
        if tc.name != TEXTURE_TAGS:
            continue
        for tag in tc.tag:
            parts = str(tag.name or "").split("|")
            if len(parts) != 3 or not parts[0].strip() or not parts[1].strip():
                raise CxfImportError(file, at, "Tag", "Name=VENDOR|NAME|GEOMETRY", tag.name)
            vendor, name, geo = parts[0], parts[1], parts[2].strip()
            try:
                value = float(tag.value or "")
            except ValueError:
                value = math.nan
            if not math.isfinite(value):
                raise CxfImportError(file, at, name, "a finite number", tag.value)
            geometry = canonical_geometry(geo, name, err) if geo else ""
            prior = texture.setdefault((vendor, name, geometry), VendorValue(vendor, name, value, geometry))
            if prior.value != value:
                raise CxfImportError(
                    file, at, name, f"one value at {geometry or 'the sample'} ({prior.value!r})", value
                )
    return list(texture.values())


def _object(obj: Any, i: int, specs: dict[str, dict[str, Any]], file: str) -> ImportedMeasurement:
    """One ``Object`` as a validated measurement (every geometry with Lab, spectra, or both)."""
    where = f"Object[{i}]"  # an index, never the file's text
    groups = _values(obj, where, specs, file)
    if not groups:
        raise CxfImportError(
            file, where, "ColorValues", "directional ColorCIELab or ReflectanceSpectrum values"
        )
    slots = [s for _, s in groups]
    has_lab = [("lab" in s) for s in slots]
    has_sp = [("spectrum" in s) for s in slots]
    if any(has_lab) and not all(has_lab):
        raise CxfImportError(file, where, "ColorCIELab", "Lab at every geometry or none")
    if any(has_sp) and not all(has_sp):
        raise CxfImportError(file, where, "ReflectanceSpectrum", "a spectrum at every geometry or none")
    wl = slots[0].get("wl")
    if any(s.get("wl") != wl for s in slots):
        raise CxfImportError(file, where, "WavelengthRange", "one wavelength grid for all geometries")
    conds = {(s["spec"]["illuminant"], s["spec"]["observer"]) for s in slots}
    if len(conds) != 1:
        raise CxfImportError(file, where, "TristimulusSpec", "one illuminant and observer per sample")
    illuminant, observer = conds.pop()
    return build_measurement(
        sample=str(obj.name or ""),
        rows=[(g, s["err"]) for g, s in groups],
        lab=[s["lab"] for s in slots] if all(has_lab) else None,
        wavelengths_nm=wl if all(has_sp) else None,
        spectra=[s["spectrum"] for s in slots] if all(has_sp) else None,
        instrument=slots[0]["spec"]["instrument"],
        illuminant=illuminant,
        observer=observer,
        measured_at=None if _undated(obj) else _instant(obj.creation_date),
        texture=_texture(obj, where, file),
        err=factory(CxfImportError, file, where),
    )


def _undated(obj: Any) -> bool:
    """Whether the writer marked the object's ``CreationDate`` as a placeholder (no measurement instant)."""
    return any(
        tc.name == UNDATED_TAGS and any(t.name == "measured_at" and t.value == "unknown" for t in tc.tag)
        for tc in obj.tag_collection
    )


def _when(instant: dt.datetime | None) -> cxf3.CreationDate:
    value = instant or dt.datetime(2000, 1, 1, tzinfo=dt.UTC)
    return cxf3.CreationDate(value=XmlDateTime.from_datetime(value.astimezone(dt.UTC)))


def write_cxf(measurements: Sequence[ImportedMeasurement], path: Path | str | None = None) -> bytes:
    """CxF3 bytes of *measurements* (layout in the module doc); written to *path* when given.

    Lab to 4 decimals, reflectance to 6. Every measurement needs a 10 nm (or any regular) grid.
    """
    if not measurements:
        raise CxfImportError(str(path or "cxf"), "", "measurements", "at least one measurement", 0)
    specs: dict[str, cxf3.ColorSpecification] = {}
    objects = []
    for i, m in enumerate(measurements, start=1):
        start: int | None = None
        step: int | None = None
        if m.wavelengths_nm is not None:
            wl = m.wavelengths_nm
            delta = wl[1] - wl[0]
            if any(abs((b - a) - delta) > 1e-9 for a, b in itertools.pairwise(wl)) or not (
                float(wl[0]).is_integer() and float(delta).is_integer()
            ):
                raise CxfImportError(
                    str(path or "cxf"), f"measurement {i}", "wavelengths_nm", "a regular whole-nm grid"
                )
            start, step = int(wl[0]), int(delta)
        values: list[Any] = []
        for k, g in enumerate(m.geometries):
            sid = f"CS{g}-{m.illuminant}-{observer_degrees(m.observer)}-{start}-{step}-{m.instrument.serial}"
            if sid not in specs:
                specs[sid] = _spec(sid, g, m, start, step)
            if m.lab is not None:
                L, a, b = (round(v, LAB_DECIMALS) for v in m.lab[k])
                values.append(cxf3.ColorCielab(l=L, a=a, b=b, color_specification=sid))
            if m.spectra is not None:
                values.append(
                    cxf3.ReflectanceSpectrum(
                        value=[round(v, SPECTRA_DECIMALS) for v in m.spectra[k]],
                        start_wl=start,
                        color_specification=sid,
                    )
                )
        tags = [
            cxf3.Tag(name=f"{t.vendor}|{t.name}|{t.geometry}", value=repr(float(t.value))) for t in m.texture
        ]
        objects.append(
            cxf3.Object(
                creation_date=_when(m.measured_at),
                color_values=cxf3.ColorValues(choice=values),
                tag_collection=([cxf3.TagCollection(tag=tags, name=TEXTURE_TAGS)] if tags else [])
                + ([] if m.measured_at is not None else [_UNDATED]),
                object_type="Target",
                name=m.sample,
                id=f"o{i}",
            )
        )
    doc = cxf3.CxF(
        file_information=cxf3.FileInformation(
            creator=CREATOR,
            creation_date=_when(measurements[0].measured_at),
            description="multi-angle measurements",
        ),
        resources=cxf3.Resources(
            object_collection=cxf3.ObjectCollection(object_value=objects),
            color_specification_collection=cxf3.ColorSpecificationCollection(
                color_specification=list(specs.values())
            ),
        ),
    )
    data = colour_cxf.write_cxf(doc)
    if path is not None:
        Path(path).write_bytes(data)
    return data


def _spec(
    sid: str, g: str, m: ImportedMeasurement, start: int | None, step: int | None
) -> cxf3.ColorSpecification:
    from station.model.domain import parse_geometry

    ill, asp = parse_geometry(g)
    observer = cxf3.EobserverType("10_Degree" if observer_degrees(m.observer) == "10" else "2_Degree")
    return cxf3.ColorSpecification(
        tristimulus_spec=cxf3.TristimulusSpec(
            illuminant_or_custom_illuminant=cxf3.Illuminant(value=cxf3.EilluminantType(m.illuminant)),
            observer=cxf3.Observer(value=observer),
            method=cxf3.Method(value=cxf3.EastmTableType("E308_Table6")),
        ),
        measurement_spec=cxf3.MeasurementSpec(
            measurement_type=cxf3.MeasurementType(value=cxf3.EspectrumType("Spectrum_Reflectance")),
            geometry_choice=cxf3.GeometryChoice(
                choice=cxf3.MultiAngleType(
                    brdfangle=[
                        cxf3.Brdfangle(
                            illumination_angle=ill,
                            aspecular=asp,
                            notation=f"{format_angle(ill)}as{format_angle(asp)}",
                        )
                    ]
                )
            ),
            wavelength_range=None if start is None else cxf3.WavelengthRange(start_wl=start, increment=step),
            device=cxf3.Device(
                manufacturer=m.instrument.manufacturer or None,
                model=m.instrument.model or None,
                serial_number=m.instrument.serial or None,
            ),
        ),
        id=sid,
    )
