"""The design file format: JSON, schema ``cacad.design/1`` (documented in docs/model.md).

A design file is a JSON object::

    {
      "schema": "cacad.design/1",          # optional on input; always written
      "name": "Red metallic",               # optional
      "face": [L, a, b],                    # Lab (D65/10°) at 15°
      "flop": [L, a, b],                    # Lab at the travel angle
      "travel_deg": 62.0,                   # θ_clamp in degrees; null for a solid
      "gloss_gu": 85.0,                     # 60° gloss units; null = not measured (default used)
      "flakes": {"size_um": 25, "density_per_mm2": 400, "spread_deg": 8, "reflectance": 0.5},
      "anisotropy": {"alpha_x": 0.05, "alpha_y": 0.25, "direction_deg": 0}
    }

``flakes`` is optional (:class:`station.model.flakes.FlakeLayer`; missing keys take its defaults): absent,
the paint type's default applies (:func:`default_flakes`: none for a solid, aluminium flakes for an effect
paint); ``null`` means no flake layer. :func:`design_from_dict` ignores it, so older readers and files
keep working; :func:`flakes_from_dict` reads it.

``anisotropy`` is optional too (:class:`station.model.anisotropy.Anisotropy`, Ward's α_x ≤ α_y and the
direction of principal anisotropy, eq 2.5.4): absent or ``null``, the design is isotropic (its own gloss
lobes); :func:`anisotropy_from_dict` reads it.

Any other keys are kept by the caller and ignored here, so the JSON printed by
``station model from-angles`` (which adds ``residual_de`` and more) is itself a valid design file.
"""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path
from typing import Any

from station.errors import InputError
from station.model.anisotropy import Anisotropy
from station.model.errors import ModelInputError
from station.model.flakes import METALLIC_FLAKES, PEARL_FLAKES, FlakeLayer, is_pearl
from station.model.representations import DEFAULT_GLOSS_GU, FaceFlopTravelGloss

SCHEMA = "cacad.design/1"
#: Largest design file accepted, bytes.
MAX_DESIGN_BYTES = 1_000_000


def design_to_dict(design: FaceFlopTravelGloss, **extra: Any) -> dict[str, Any]:
    """Serialise a design to the ``cacad.design/1`` JSON object (plus *extra* keys)."""
    out: dict[str, Any] = {
        "schema": SCHEMA,
        "name": design.name,
        "face": list(design.face),
        "flop": list(design.flop),
        "travel_deg": design.travel_deg,
        "gloss_gu": design.gloss_target_gu,  # null: not measured (the default renders, nothing is matted)
    }
    out.update(extra)
    return out


def design_from_dict(data: Any) -> FaceFlopTravelGloss:
    """Parse a ``cacad.design/1`` JSON object; unknown keys are ignored.

    Raises
    ------
    ModelInputError
        Naming the missing or invalid field and the accepted range.
    """
    if not isinstance(data, dict):
        raise ModelInputError(
            "design", "a JSON object with face, flop, travel_deg, gloss_gu", type(data).__name__
        )
    schema = data.get("schema", SCHEMA)
    if schema != SCHEMA:
        raise ModelInputError("schema", f'"{SCHEMA}"', schema)
    for key in ("face", "flop"):
        if key not in data:
            raise ModelInputError(key, "[L, a, b] (required)", None)
    if "travel_deg" not in data:
        raise ModelInputError(
            "travel_deg", "degrees (15 < travel <= 180) or null for a solid (required)", None
        )
    gloss = data.get("gloss_gu")
    name = data.get("name") or ""
    if not isinstance(name, str):
        raise ModelInputError("name", "a string", name)
    return FaceFlopTravelGloss(
        face=data["face"],
        flop=data["flop"],
        travel_deg=data["travel_deg"],
        gloss_gu=DEFAULT_GLOSS_GU if gloss is None else gloss,
        name=name,
        gloss_measured=gloss is not None,
    )


def default_flakes(design: FaceFlopTravelGloss) -> FlakeLayer | None:
    """The paint type's default flake layer: None for a solid (no travel), PEARL_FLAKES for a hue-shifting
    pearl (:func:`station.model.flakes.is_pearl`), METALLIC_FLAKES otherwise."""
    if design.travel_deg is None:
        return None
    return PEARL_FLAKES if is_pearl(design.face, design.flop) else METALLIC_FLAKES


def flakes_from_dict(data: Any, design: FaceFlopTravelGloss | None = None) -> FlakeLayer | None:
    """The design file's flake layer (module docstring); ModelInputError names ``flakes.<field>``."""
    if not isinstance(data, dict) or "flakes" not in data:
        return default_flakes(design if design is not None else design_from_dict(data))
    if data["flakes"] is None:
        return None
    return FlakeLayer.from_dict(data["flakes"])


def anisotropy_from_dict(data: Any) -> Anisotropy | None:
    """The design file's anisotropy (module docstring): None (isotropic) when absent or null."""
    if not isinstance(data, dict) or data.get("anisotropy") is None:
        return None
    return Anisotropy.from_dict(data["anisotropy"])


def read_json_file(
    path: str | Path,
    field: str,
    what: str,
    max_bytes: int,
    error: Callable[[str, str, Any], InputError] = ModelInputError,
) -> Any:
    """Parse a size-capped UTF-8 JSON file (design, palette and mood-board files share this reader).

    ``field`` and ``what`` name the file in the error: a missing file, one above ``max_bytes`` bytes, or one
    that is not UTF-8 JSON raises ``error(field, accepted, got)`` (an :class:`InputError`).
    """
    p = Path(path)
    try:
        size = p.stat().st_size
    except OSError as exc:
        raise error(field, f"a readable {what}", str(p)) from exc
    if size > max_bytes:
        raise error(field, f"a file of at most {max_bytes} bytes", size)
    try:
        return json.loads(p.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise error(field, f"a JSON {what}", f"{p}: {exc}") from exc


def load_design(path: str | Path) -> FaceFlopTravelGloss:
    """Read a design file (``cacad.design/1`` JSON); errors name the file and the field."""
    return design_from_dict(read_json_file(path, "design", f"design file ({SCHEMA})", MAX_DESIGN_BYTES))


def load_design_flakes(path: str | Path) -> tuple[FaceFlopTravelGloss, FlakeLayer | None]:
    """Read a design file with its flake layer (:func:`flakes_from_dict`)."""
    data = read_json_file(path, "design", f"design file ({SCHEMA})", MAX_DESIGN_BYTES)
    design = design_from_dict(data)
    return design, flakes_from_dict(data, design)


def load_design_anisotropy(path: str | Path) -> tuple[FaceFlopTravelGloss, Anisotropy | None]:
    """Read a design file with its anisotropy (:func:`anisotropy_from_dict`)."""
    data = read_json_file(path, "design", f"design file ({SCHEMA})", MAX_DESIGN_BYTES)
    return design_from_dict(data), anisotropy_from_dict(data)


def save_design(design: FaceFlopTravelGloss, path: str | Path, **extra: Any) -> Path:
    """Write a design file; returns the path."""
    p = Path(path)
    p.write_text(json.dumps(design_to_dict(design, **extra), indent=2) + "\n", encoding="utf-8")
    return p
