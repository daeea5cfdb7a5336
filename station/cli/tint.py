"""``station tint``: correct a sprayed batch by tinting additions, from its measured panel.

``station tint RECIPE --measured READING | --db URL --measurement ID [--tolerance 1.0]
[--scale-resolution G] [--json]``

RECIPE is the batch in the can: ``station formulate --json`` output (its ``design_lab``, ``angles_deg``,
``line``, ``batch`` in grams) or the ``--json`` output of an earlier ``station tint`` (the batch after
its additions). The panel sprayed from it is read from a measurement file (``station measure --json``
output, CxF3, CGATS.17, the CSV template) or from the measurement database by its id (``station measure
--store``). The answer is the add-only additions in grams, rounded to the scale, within the batch's
bounds (:func:`station.formulate.closed_loop.correct_batch`), the ΔE00 the panel measured and the ΔE00
the next panel is predicted to read; or, when only a new batch reaches the target, the advice to remake
and the new recipe. Nothing is written: the output, saved, is the next RECIPE and the next panel's
recipe for ``station measure sim:… --recipe``.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

import numpy as np

from station.cli._common import add_json_flag
from station.errors import InputError

#: Formats of a RECIPE file: what ``station formulate --json`` and ``station tint --json`` print.
RECIPE_FORMAT = "station formulate --json or station tint --json output"


def _read_json(path: Path, field: str) -> dict[str, Any]:
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(field, f"a readable JSON file ({RECIPE_FORMAT})", str(path)) from exc
    try:
        data = json.loads(text)
    except json.JSONDecodeError as exc:
        raise InputError(field, f"JSON ({RECIPE_FORMAT})", str(path)) from exc
    if not isinstance(data, dict):
        raise InputError(field, f"a JSON object ({RECIPE_FORMAT})", type(data).__name__)
    return data


def _field(data: dict[str, Any], key: str, kind: type | tuple[type, ...], accepted: str) -> Any:
    value = data.get(key)
    if not isinstance(value, kind) or isinstance(value, bool):
        raise InputError(f"recipe.{key}", accepted, value)
    return value


def _recipe(path: Path) -> dict[str, Any]:
    """The batch in the can and its design from a RECIPE file (each field checked and named)."""
    from station.model.domain import TONER_LINES

    data = _read_json(path, "recipe_file")
    angles = _field(data, "angles_deg", list, "aspecular angles in degrees, e.g. [15, 45, 110]")
    if not angles or not all(isinstance(a, int | float) and not isinstance(a, bool) for a in angles):
        raise InputError("recipe.angles_deg", "aspecular angles in degrees, e.g. [15, 45, 110]", angles)
    design = _field(data, "design_lab", list, "Lab per angle of angles_deg")
    line = data.get("line")
    if line is not None and line not in TONER_LINES:
        raise InputError("recipe.line", " | ".join(TONER_LINES), line)
    batch = _field(data, "batch", dict, "the batch in grams: {colorants_g, binder_g, total_g}")
    colorants = batch.get("colorants_g")
    if not isinstance(colorants, dict):
        raise InputError("recipe.batch.colorants_g", "grams per colorant", colorants)
    total = data.get("first_batch_g", batch.get("total_g"))
    if isinstance(total, bool) or not isinstance(total, int | float) or not np.isfinite(total) or total <= 0:
        raise InputError("recipe.batch.total_g", "the batch's mass in g > 0", total)
    gloss = data.get("gloss_gu")
    return {
        "design": data.get("design", path.stem),
        "angles": tuple(float(a) for a in angles),
        "design_lab": design,
        "line": line,
        "colorants_g": colorants,
        "binder_g": batch.get("binder_g"),
        "first_batch_g": float(total),
        "gloss_gu": gloss if isinstance(gloss, int | float) and not isinstance(gloss, bool) else None,
        "scale_resolution_g": _resolution(data),
    }


def _resolution(data: dict[str, Any]) -> float | None:
    """The scale resolution (g) the RECIPE was weighed at: its own field (``station tint``) or its first
    recipe's (``station formulate``); None when it names none."""
    recipes = data.get("recipes")
    first = recipes[0] if isinstance(recipes, list) and recipes and isinstance(recipes[0], dict) else {}
    value = data.get("scale_resolution_g", first.get("scale_resolution_g"))
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise InputError("recipe.scale_resolution_g", "the scale's resolution in g (a number)", value)
    return float(value)


def _reading(args: argparse.Namespace) -> Any:
    """The measured panel: a measurement file, or a stored measurement by id."""
    from station.qc.readings import load_readings, reading_from_measurement

    if (args.measured is None) == (args.measurement is None):
        raise InputError("--measured", "either --measured FILE or --db URL --measurement ID", None)
    if args.measured is not None:
        if not Path(args.measured).is_file():
            raise InputError("--measured", "an existing measurement file", str(args.measured))
        readings = load_readings(args.measured)
        if len(readings) != 1:
            raise InputError("--measured", "a file of one reading (one panel)", f"{len(readings)} readings")
        return readings[0]
    from station.cli._qc_db import _session
    from station.qc.jobs import current_measurement

    with _session(args) as session:
        m = current_measurement(session, args.measurement)
        if m is None:
            raise InputError("--measurement", "the id of a stored measurement", args.measurement)
        return reading_from_measurement(m)


def _measured_lab(reading: Any, angles: tuple[float, ...]) -> np.ndarray:
    """The reading's Lab at the recipe's angles; a reading of another geometry set is refused."""
    from station.model.domain import aspecular_name

    index = {a: i for i, a in enumerate(reading.aspecular_deg)}
    missing = [aspecular_name(a) for a in angles if a not in index]
    if missing:
        raise InputError(
            "measured.geometries",
            f"the recipe's geometries {', '.join(aspecular_name(a) for a in angles)} (missing "
            f"{', '.join(missing)})",
            list(reading.geometries),
        )
    return np.asarray(reading.lab_array())[[index[a] for a in angles]]


def _option_field(field: str) -> str:
    """The command line's name of a core field: an option, or a field of the RECIPE file or the reading."""
    if field == "scale_resolution_g":
        return "--scale-resolution"
    if field == "batch_g":
        return "recipe.batch.total_g"
    if field.startswith("measured_lab"):
        return "measured.lab" + field.removeprefix("measured_lab")
    return field if field.startswith("recipe.") else f"recipe.{field}"


def cmd_tint(args: argparse.Namespace) -> dict[str, Any]:
    """Correct the batch of RECIPE by tinting additions from its measured panel."""
    from station.formulate.closed_loop import correct_batch
    from station.formulate.errors import FormulateInputError
    from station.formulate.formulation import FormulationOptions, formulation_options
    from station.model.domain import DEFAULT_SCALE_RESOLUTION_G

    if not (np.isfinite(args.tolerance) and args.tolerance > 0):
        raise InputError("--tolerance", "a mean ΔE00 > 0", args.tolerance)
    if not Path(args.recipe).is_file():
        raise InputError("recipe_file", f"an existing recipe file ({RECIPE_FORMAT})", str(args.recipe))
    rec = _recipe(Path(args.recipe))
    lab = _measured_lab(_reading(args), rec["angles"])
    resolution = next(
        r
        for r in (args.scale_resolution, rec["scale_resolution_g"], DEFAULT_SCALE_RESOLUTION_G)
        if r is not None
    )
    try:
        options = formulation_options(
            FormulationOptions(line=rec["line"], scale_resolution_g=resolution, batch_g=rec["first_batch_g"])
        )
        fix = correct_batch(
            rec["design_lab"],
            lab,
            rec["colorants_g"],
            rec["binder_g"],
            rec["angles"],
            tolerance=args.tolerance,
            options=options,
            gloss_gu=rec["gloss_gu"],
        )
    except FormulateInputError as exc:
        raise InputError(_option_field(exc.field), exc.accepted, exc.got) from exc
    out: dict[str, Any] = {
        "design": rec["design"],
        "line": rec["line"],
        "angles_deg": list(fix.angles_deg),
        "design_lab": [list(map(float, r)) for r in rec["design_lab"]],
        "measured_lab": lab.tolist(),
        "measured_de": list(fix.measured_de),
        "measured_mean_de": fix.measured_mean_de,
        "remake": fix.tinting.remake,
        "additions_g": dict(fix.tinting.additions_g),
        "binder_added_g": fix.tinting.binder_g,
        "message": fix.tinting.message,
        "recipe": fix.recipe,
        "batch": {"colorants_g": fix.masses_g, "binder_g": fix.binder_g, "total_g": fix.tinting.new_total_g},
        "first_batch_g": rec["first_batch_g"],
        "scale_resolution_g": resolution,
        "gloss_gu": rec["gloss_gu"],
        "target_lab": [list(r) for r in fix.target_lab],
        "predicted_lab": [list(r) for r in fix.predicted_lab],
        "predicted_mean_de": fix.predicted_mean_de,
        "tolerance": args.tolerance,
        "synthetic_colorants": True,
    }
    if not args.json:
        adds = ", ".join(f"{n} {g:g} g" for n, g in sorted(out["additions_g"].items()))
        out["summary"] = (
            f"measured mean ΔE00 {fix.measured_mean_de:.2f}; "
            + (
                f"remake: {fix.tinting.message}"
                if fix.tinting.remake
                else f"add {adds}"
                if adds
                else fix.tinting.message
            )
            + (f", binder {fix.tinting.binder_g:g} g" if fix.tinting.binder_g > 0 else "")
            + f"; predicted mean ΔE00 after {fix.predicted_mean_de:.2f}"
        )
    return out


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add ``station tint``."""
    from station.model.domain import SCALE_RESOLUTION_RANGE_G

    p = subparsers.add_parser(
        "tint",
        help="correct a sprayed batch by tinting additions (g) from its measured panel",
        description="Add-only additions (g, rounded to the scale) that bring the batch of RECIPE "
        "toward its design, from the panel sprayed from it and measured; or the advice to remake "
        "with the new recipe when additions cannot reach it. Nothing is stored.",
    )
    p.add_argument("recipe", type=Path, metavar="RECIPE", help=f"the batch in the can: {RECIPE_FORMAT}")
    p.add_argument(
        "--measured",
        type=Path,
        help="the panel's reading: station measure --json output, CxF3, CGATS.17 or the CSV template",
    )
    p.add_argument("--db", help="measurement database URL of --measurement (default: the service's)")
    p.add_argument("--measurement", type=int, help="id of the stored reading of the panel (with --db)")
    p.add_argument("--tolerance", type=float, default=1.0, help="mean ΔE00 aimed within (default 1.0)")
    p.add_argument(
        "--scale-resolution",
        type=float,
        help=f"scale resolution in g the additions are rounded to ({SCALE_RESOLUTION_RANGE_G[0]:g}-"
        f"{SCALE_RESOLUTION_RANGE_G[1]:g}; default: the recipe's)",
    )
    add_json_flag(p)
    p.set_defaults(handler=cmd_tint)
