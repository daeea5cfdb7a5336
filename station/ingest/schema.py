"""The reading a station sends to ingest: validated, canonically serialised and hashed.

Units: aspecular angles in degrees; Lab is CIE L*a*b* (D65 / CIE 1964 10° unless ``illuminant`` and
``observer`` say otherwise); reflectance factors are unitless (metallic faces exceed 1 at 15°);
wavelengths in nanometres; gloss in gloss units at ``gloss_geometry_deg`` (ISO 2813: 20°, 60°, 85°);
``illumination_deg`` is the illumination angle of the block the aspecular angles belong to (45° unless an
instrument with a second block, an MA-T12's 15°, says otherwise); ``texture`` holds vendor texture values
(sparkle, graininess: unitless, device-dependent, tagged with the vendor whose procedure made them).
"""

from __future__ import annotations

import base64
import binascii
import datetime as dt
import hashlib
import json
import uuid
from typing import Annotated, Literal

from pydantic import (
    AfterValidator,
    AwareDatetime,
    BaseModel,
    ConfigDict,
    Field,
    field_validator,
    model_validator,
)

from db.models.measurements import PARTS
from station.model.domain import ILLUMINATION_DEG, LAB_HI, LAB_LO, geometry_name, parse_geometry
from station.model.errors import ModelInputError
from station.schema_config import strict_config

# strict=True: a JSON true or "55.3" is refused, not read as a number (an integer is a float).
Angle = Annotated[
    float,
    Field(strict=True, gt=-90.0, lt=180.0, allow_inf_nan=False, description="aspecular angle, degrees"),
]
LabTriple = Annotated[
    # The envelope of the domain's Lab bound (station.model.domain); each channel is checked there.
    list[Annotated[float, Field(strict=True, ge=min(LAB_LO), le=max(LAB_HI), allow_inf_nan=False)]],
    Field(min_length=3, max_length=3, description="[L*, a*, b*]"),
]
Reflectance = Annotated[float, Field(strict=True, ge=0.0, le=10.0, allow_inf_nan=False)]
Illuminant = Literal["D65", "D50", "A", "C", "F2", "F7", "F11"]
Observer = Literal["CIE 1931 2 Degree Standard Observer", "CIE 1964 10 Degree Standard Observer"]
Text64 = Annotated[str, Field(min_length=1, max_length=64, pattern=r"^[^\x00-\x1f]+$")]

#: Accepted instants of a reading or a calibration (UTC): beyond them a time-zone shift overflows.
EARLIEST = dt.datetime(1970, 1, 1, tzinfo=dt.UTC)
LATEST = dt.datetime(2200, 1, 1, tzinfo=dt.UTC)


def _bounded_instant(value: dt.datetime) -> dt.datetime:
    """*value* (time-zone aware) if it lies in [EARLIEST, LATEST); ``0001-01-01T00:00+05:00`` is refused."""
    try:
        utc = value.astimezone(dt.UTC)
    except (OverflowError, ValueError) as exc:
        raise ValueError(f"expected an instant in [{EARLIEST:%Y-%m-%d}, {LATEST:%Y-%m-%d}) UTC") from exc
    if not EARLIEST <= utc < LATEST:
        raise ValueError(f"expected an instant in [{EARLIEST:%Y-%m-%d}, {LATEST:%Y-%m-%d}) UTC")
    return value


Timestamp = Annotated[AwareDatetime, AfterValidator(_bounded_instant)]

MAX_GEOMETRIES = 12
MAX_WAVELENGTHS = 81
MAX_RAW_BYTES = 65_536
#: Texture values one reading may carry (a few quantities per geometry).
MAX_TEXTURE = 8 * MAX_GEOMETRIES


class InstrumentRef(BaseModel):
    """The instrument that took the reading (created on first sight, keyed by serial)."""

    model_config = ConfigDict(extra="forbid")

    serial: Text64
    model: Text64
    kind: Annotated[str, Field(min_length=1, max_length=32, pattern=r"^[a-z0-9_-]+$")] = "multiangle"
    firmware: Annotated[str, Field(max_length=32)] | None = None


class CalibrationRef(BaseModel):
    """The calibration in force when the reading was taken (keyed by its client id)."""

    model_config = ConfigDict(extra="forbid")

    client_id: uuid.UUID
    performed_at: Timestamp
    reference: Annotated[str, Field(max_length=64)] = ""
    passed: bool = True


class PanelRef(BaseModel):
    """A panel named by its metadata: the lowest-id panel with the same four fields, else created with the reading.

    ``part`` is one of ``db.models.PARTS``; the limits are the database columns' (job and substrate 64
    characters, notes 4000).
    """

    model_config = ConfigDict(extra="forbid")

    job: Text64
    part: str
    substrate: Annotated[str, Field(max_length=64)] = ""
    notes: Annotated[str, Field(max_length=4000)] = ""

    @field_validator("part")
    @classmethod
    def _known_part(cls, value: str) -> str:
        if value not in PARTS:
            raise ValueError(f"part: expected one of {' | '.join(PARTS)}, got {value!r}")
        return value


class TextureValue(BaseModel):
    """A vendor texture value (sparkle, graininess; unitless) as the vendor's software computed it.

    ``geometry`` is the geometry name it belongs to (``45as15``; stored in the domain's spelling) or
    ``""`` for a per-sample value (graininess is measured under diffuse light). Values of different
    vendors are never compared (``station.ingest.formats.VendorValue.difference`` refuses).
    """

    model_config = ConfigDict(extra="forbid", frozen=True)

    vendor: Text64
    name: Text64
    geometry: Annotated[str, Field(max_length=16)] = ""
    value: Annotated[float, Field(strict=True, ge=-1e6, le=1e6, allow_inf_nan=False)]

    @field_validator("geometry")
    @classmethod
    def _geometry(cls, value: str) -> str:
        if value == "":
            return value
        try:
            return geometry_name(*parse_geometry(value.strip().lower(), "texture.geometry"))
        except ModelInputError as exc:
            raise ValueError(f"geometry: expected {exc.accepted} or empty, got {value!r}") from exc


class Reading(BaseModel):
    """One instrument reading as sent by a station; ``client_id`` makes re-sending idempotent."""

    model_config = strict_config(
        examples=[
            {
                "client_id": "5b0c8a54-3f7e-4f56-9a53-0d1f4c1f7a10",
                "instrument": {"serial": "SIM-MA-0001", "model": "MA-98 simulator", "kind": "multiangle"},
                "panel_id": None,
                "operator": "ana",
                "measured_at": "2026-11-23T08:30:00Z",
                "geometries_deg": [15.0, 45.0, 110.0],
                "lab": [[82.1, -1.2, -18.5], [55.3, -0.4, -12.0], [31.9, 0.8, -6.2]],
                "gloss_gu": 88.0,
                "gloss_geometry_deg": 60,
            }
        ]
    )

    client_id: uuid.UUID
    instrument: InstrumentRef
    calibration: CalibrationRef | None = None
    panel_id: Annotated[int, Field(strict=True, ge=1, le=2**31 - 1)] | None = None
    panel: PanelRef | None = None
    operator: Text64
    measured_at: Timestamp
    illumination_deg: Annotated[
        float,
        Field(strict=True, gt=0.0, lt=90.0, allow_inf_nan=False, description="illumination angle, degrees"),
    ] = ILLUMINATION_DEG
    illuminant: Illuminant = "D65"
    observer: Observer = "CIE 1964 10 Degree Standard Observer"
    geometries_deg: Annotated[list[Angle], Field(min_length=1, max_length=MAX_GEOMETRIES)]
    lab: Annotated[list[LabTriple], Field(min_length=1, max_length=MAX_GEOMETRIES)]
    wavelengths_nm: (
        Annotated[
            list[Annotated[float, Field(strict=True, ge=300.0, le=1100.0, allow_inf_nan=False)]],
            Field(min_length=2, max_length=MAX_WAVELENGTHS),
        ]
        | None
    ) = None
    spectra: (
        Annotated[
            list[Annotated[list[Reflectance], Field(max_length=MAX_WAVELENGTHS)]],
            Field(max_length=MAX_GEOMETRIES),
        ]
        | None
    ) = None
    gloss_gu: Annotated[float, Field(strict=True, ge=0.0, le=2000.0, allow_inf_nan=False)] | None = None
    gloss_geometry_deg: Literal[20, 60, 85] | None = None
    raw_payload_b64: Annotated[str, Field(max_length=(MAX_RAW_BYTES * 4) // 3 + 4)] | None = None
    texture: Annotated[list[TextureValue], Field(max_length=MAX_TEXTURE)] | None = None

    @model_validator(mode="after")
    def _consistent(self) -> Reading:
        if self.panel_id is not None and self.panel is not None:
            raise ValueError("panel: expected panel_id or panel metadata, not both")
        if len(self.lab) != len(self.geometries_deg):
            raise ValueError(
                f"lab: expected one [L*, a*, b*] per geometry ({len(self.geometries_deg)}), "
                f"got {len(self.lab)}"
            )
        if len(set(self.geometries_deg)) != len(self.geometries_deg):
            raise ValueError("geometries_deg: expected distinct angles")
        if (self.spectra is None) != (self.wavelengths_nm is None):
            raise ValueError("spectra and wavelengths_nm: expected both or neither")
        if self.spectra is not None and self.wavelengths_nm is not None:
            if len(self.spectra) != len(self.geometries_deg):
                raise ValueError("spectra: expected one curve per geometry")
            if any(len(curve) != len(self.wavelengths_nm) for curve in self.spectra):
                raise ValueError("spectra: expected each curve to have one value per wavelength")
            if any(b <= a for a, b in zip(self.wavelengths_nm, self.wavelengths_nm[1:], strict=False)):
                raise ValueError("wavelengths_nm: expected strictly increasing values")
        if self.gloss_gu is not None and self.gloss_geometry_deg is None:
            self.gloss_geometry_deg = 60
        if self.texture is not None:
            self._check_texture(self.texture)
            if not self.texture:
                self.texture = None  # no texture values: stored and hashed as none at all
        if self.raw_payload_b64 is not None:
            try:
                raw = base64.b64decode(self.raw_payload_b64, validate=True)
            except binascii.Error as exc:
                raise ValueError("raw_payload_b64: expected base64") from exc
            if len(raw) > MAX_RAW_BYTES:
                raise ValueError(f"raw_payload_b64: expected at most {MAX_RAW_BYTES} bytes")
        return self

    def _check_texture(self, texture: list[TextureValue]) -> None:
        seen: set[tuple[str, str, str]] = set()
        for i, t in enumerate(texture):
            key = (t.vendor, t.name, t.geometry)
            if key in seen:
                raise ValueError(f"texture[{i}]: expected each vendor, name and geometry once, got {key}")
            seen.add(key)
            if t.geometry:
                ill, asp = parse_geometry(t.geometry)
                if ill != self.illumination_deg or asp not in self.geometries_deg:
                    raise ValueError(
                        f"texture[{i}].geometry: expected a geometry of this reading "
                        f"({', '.join(geometry_name(self.illumination_deg, a) for a in self.geometries_deg)}) "
                        f"or empty, got {t.geometry!r}"
                    )

    def canonical_json(self) -> str:
        """The reading as compact JSON with sorted keys (what the outbox stores).

        ``panel`` and ``texture`` are left out when absent and ``illumination_deg`` when it is 45°, so a
        reading without them hashes as it always has (and an older outbox body still decodes).
        """
        exclude = {
            name
            for name, absent in (
                ("panel", self.panel is None),
                ("texture", self.texture is None),
                ("illumination_deg", self.illumination_deg == ILLUMINATION_DEG),
            )
            if absent
        }
        body = self.model_dump(mode="json", exclude=exclude or None)
        return json.dumps(body, sort_keys=True, separators=(",", ":"))

    def payload_sha256(self) -> str:
        """SHA-256 of the raw instrument payload when given, else of :meth:`canonical_json`."""
        if self.raw_payload_b64 is not None:
            return hashlib.sha256(base64.b64decode(self.raw_payload_b64)).hexdigest()
        return hashlib.sha256(self.canonical_json().encode()).hexdigest()
