"""``station analysis …``: misalignment QA from the command line (thesis ch. 4).

* ``gg-index`` — goniogeometric index β_min (eq 4.3.1) of a paint for a point light and view(s).
* ``trompe-loeil`` — inverse trompe l'oeil: paint B for a misaligned panel (§4.4).
* ``seam`` — QA of two panels (design or measurement JSON): seam ΔE, index, pass/fail, §4.5 advice,
  corrected paint; ``--png`` writes the report picture.
* ``sweep`` — seam ΔE over view × light × β (Fig. 4.3), optionally as a PNG.

Lists that start with a minus sign need the ``=`` form: ``--views=-30,0`` (argparse would read
``-30,0`` as an option).

Environment lighting is available from Python and the service (``station.analysis.Environment``, built
from a ``station.render`` environment by the caller); the CLI takes point lights.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import TYPE_CHECKING, Any

from station.analysis.options import DEFAULT_ASPECULAR_DEG, DEFAULT_LIGHTS_DEG, OBJECTIVES
from station.cli._common import add_json_flag, design_from_args, parse_floats
from station.errors import InputError
from station.model.domain import DELTA_E_COMPUTED, JND_CIE76

if TYPE_CHECKING:
    from station.analysis.geometry import Hinge


def _hinge(text: str) -> Hinge:
    if text == "in-plane":
        return "in-plane"
    if text == "out-of-plane":
        return "out-of-plane"
    return parse_floats(text, "hinge", 1)[0]


def _add_paint_args(p: argparse.ArgumentParser) -> None:
    p.add_argument("--design", help="design JSON file (cacad.design/1) instead of --face/--flop/--travel")
    p.add_argument("--face", help="face Lab at 15°: L,a,b")
    p.add_argument("--flop", help="flop Lab: L,a,b (default = face: a solid)")
    p.add_argument("--travel", type=float, help="travel θ_clamp in degrees (effect paints)")
    p.add_argument("--gloss", type=float, help="gloss in GU (used only with --include-gloss)")


def _add_common(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--epsilon", type=float, default=JND_CIE76, help="ΔE threshold (default 2.3 = 1 JND ΔE*ab)"
    )
    p.add_argument("--de", choices=DELTA_E_COMPUTED, default="cie76", help="colour-difference formula")
    p.add_argument("--hinge", default="in-plane", help="in-plane | out-of-plane | hinge azimuth in degrees")


def _common(args: argparse.Namespace) -> dict[str, Any]:
    """The options of :func:`_add_common` as the ``station.analysis`` keywords (ε, ΔE formula, hinge)."""
    return {"epsilon": args.epsilon, "method": args.de, "hinge": _hinge(args.hinge)}


def _paint_and_geometry(
    args: argparse.Namespace, light: str, view: str
) -> tuple[Any, list[float], list[float] | None]:
    """The paint, the light polar angles of option *light* and the view angles of option *view* (degrees;
    ``None`` when not given)."""
    paint = design_from_args(args)
    lights = parse_floats(getattr(args, light), light)
    views = parse_floats(getattr(args, view), view) if getattr(args, view) is not None else None
    return paint, lights, views


def _gg_index(args: argparse.Namespace) -> dict[str, Any]:
    from station.analysis import goniogeometric_index

    paint, lights, views = _paint_and_geometry(args, "light", "view")
    r = goniogeometric_index(
        paint,
        lights,
        views,
        direction=args.direction,
        beta_max_deg=args.beta_max,
        gloss=args.include_gloss,
        **_common(args),
    )
    return r.to_dict(per_geometry=args.per_geometry)


def _trompe(args: argparse.Namespace) -> dict[str, Any]:
    from station.analysis.trompe import inverse_trompe_loeil

    paint, lights, views = _paint_and_geometry(args, "lights", "views")
    r = inverse_trompe_loeil(
        paint,
        lights,
        views,
        beta_deg=args.beta,
        objective=args.objective,
        at=args.at,
        subset=args.subset,
        allow_face_darker=args.allow_face_darker,
        **_common(args),
    )
    return r.to_dict()


def load_panel(path: str, illuminant: str = "D65") -> Any:
    """A panel from a design JSON (``cacad.design/1``) or a measurement JSON.

    Measurement JSON: ``{"angles_deg": [...], "lab": [[L, a, b], ...], "gloss_gu": g}`` (Lab D65/10°,
    illumination at 45°), or the output of ``station measure --json`` (``"geometries"`` named like
    ``45as15`` beside ``"lab"``: its positive aspecular angles under 45° illumination are taken, as the
    viewer fits a scan); it is fitted to face/flop/travel (eqs 3.3.1–3.3.10).

    Under an *illuminant* other than D65 the measurement must carry ``"spectra"`` (one 400–700 nm,
    10 nm reflectance per row, ``"wavelengths_nm"`` optional) and its Lab is taken from them under that
    illuminant (:func:`station.analysis.measurements_under`); a design or a Lab-only file is refused.
    """
    import numpy as np

    from station.model import AspecularMeasurements
    from station.model.design_io import design_from_dict
    from station.model.domain import ILLUMINATION_DEG, parse_geometry
    from station.model.illuminants import illuminant_name

    try:
        data = json.loads(Path(path).read_text())
    except (OSError, ValueError) as exc:
        raise InputError("panel", "a readable JSON file (design or measurement)", path) from exc
    if not isinstance(data, dict):
        raise InputError("panel", "a JSON object", path)
    if illuminant_name(illuminant) != "D65":
        return _panel_under(data, path, illuminant)
    if "angles_deg" in data and "lab" in data:
        return AspecularMeasurements(tuple(data["angles_deg"]), data["lab"], data.get("gloss_gu"))
    if "geometries" in data and "lab" in data:  # station measure --json
        names, lab = data["geometries"], data["lab"]
        if not isinstance(names, list) or not isinstance(lab, list) or len(names) != len(lab):
            raise InputError("panel", "a measurement with one Lab row per geometry", path)
        rows = sorted(
            (asp, row)
            for name, row in zip(names, lab, strict=True)
            for illum, asp in [parse_geometry(name, "panel geometries")]
            if illum == ILLUMINATION_DEG and asp > 0
        )
        if len(rows) < 3:
            raise InputError(
                "panel", "a measurement with at least 3 positive aspecular angles under 45° light", path
            )
        lab_rows = np.asarray([r for _, r in rows], dtype=float)
        return AspecularMeasurements(tuple(a for a, _ in rows), lab_rows, data.get("gloss_gu"))
    return design_from_dict(data)


def _panel_under(data: dict[str, Any], path: str, illuminant: str) -> Any:
    """A measurement file's panel with its Lab from its spectra under *illuminant* (see :func:`load_panel`)."""
    from station.analysis import measurements_under
    from station.model.domain import ILLUMINATION_DEG, parse_geometry
    from station.model.illuminants import illuminant_name
    from station.model.spectra import WAVELENGTHS

    name = illuminant_name(illuminant)
    need = f"a measurement with spectra (400–700 nm, 10 nm) to judge under {name}"
    spectra = data.get("spectra")
    if not isinstance(spectra, list) or not spectra:
        raise InputError("panel", need, path)
    wl = data.get("wavelengths_nm")
    if wl is not None and [float(w) for w in wl] != WAVELENGTHS.tolist():
        raise InputError("panel", need, path, detail="other wavelengths")
    if "angles_deg" in data:
        angles, rows = list(data["angles_deg"]), spectra
    elif isinstance(data.get("geometries"), list) and len(data["geometries"]) == len(spectra):
        picked = sorted(
            (asp, row)
            for geo, row in zip(data["geometries"], spectra, strict=True)
            for illum, asp in [parse_geometry(geo, "panel geometries")]
            if illum == ILLUMINATION_DEG and asp > 0
        )
        angles, rows = [a for a, _ in picked], [r for _, r in picked]
    else:
        raise InputError("panel", need, path)
    if len(angles) < 3:
        raise InputError(
            "panel", "a measurement with at least 3 positive aspecular angles under 45° light", path
        )
    return measurements_under(angles, rows, name, data.get("gloss_gu"), field="panel")


def _seam(args: argparse.Namespace) -> dict[str, Any]:
    from station.analysis.qa import seam_qa

    a = load_panel(args.panel_a, args.illuminant)
    b = load_panel(args.panel_b, args.illuminant)
    r = seam_qa(
        a,
        b,
        args.beta,
        lights_deg=parse_floats(args.lights, "lights"),
        aspecular_deg=parse_floats(args.aspecular, "aspecular"),
        tolerance=args.epsilon,
        method=args.de,
        hinge=_hinge(args.hinge),
        objective=args.objective,
        illuminant=args.illuminant,
    )
    out = r.to_dict()
    from station.formulate.gamut import colorant_gamut

    # the QA step flags a corrected paint the colorants cannot mix, with the nearest achievable paint
    out["corrected_colorant_gamut"] = colorant_gamut(r.correction.paint).to_dict()
    if args.png:
        from station.analysis.picture import plot_seam_report

        out["png"] = str(plot_seam_report(r, args.png))
    return out


def _sweep(args: argparse.Namespace) -> dict[str, Any]:
    from station.analysis.sweep import plot_sweep, seam_sweep

    paint = design_from_args(args)
    r = seam_sweep(
        paint,
        parse_floats(args.betas, "betas"),
        parse_floats(args.lights, "lights"),
        parse_floats(args.views, "views") if args.views else None,
        **_common(args),
    )
    out: dict[str, Any] = {"index_estimate_deg": r.index_estimate(), "shape": list(r.delta_e.shape)}
    if args.png:
        out["png"] = str(plot_sweep(r, args.png))
    else:
        out.update(r.to_dict())
    return out


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add ``station analysis …``."""
    top = subparsers.add_parser(
        "analysis", help="misalignment QA: goniogeometric index, inverse trompe l'oeil"
    )
    sub = top.add_subparsers(dest="analysis_command", required=True, metavar="SUBCOMMAND")
    for add in (_add_gg_index, _add_trompe, _add_seam, _add_sweep):
        add(sub)


def _add_gg_index(sub: argparse._SubParsersAction) -> None:
    """Add ``station analysis gg-index``: the goniogeometric index β_min (eq 4.3.1)."""
    p = sub.add_parser("gg-index", help="goniogeometric index β_min (eq 4.3.1)")
    _add_paint_args(p)
    p.add_argument("--light", required=True, help="light polar angle(s) in degrees, comma-separated")
    p.add_argument(
        "--view",
        help="view polar angle(s) in degrees (signed; default: aspecular 15–110° scan); "
        "write --view=-30,0 when the list starts with a minus",
    )
    p.add_argument("--direction", choices=("+", "-", "either"), default="either")
    p.add_argument("--beta-max", type=float, default=30.0, help="largest β searched, degrees")
    p.add_argument("--include-gloss", action="store_true", help="add the gloss lobe (excluded in the thesis)")
    p.add_argument("--per-geometry", action="store_true", help="list β_min for every geometry")
    _add_common(p)
    add_json_flag(p)
    p.set_defaults(handler=_gg_index)


def _add_trompe(sub: argparse._SubParsersAction) -> None:
    """Add ``station analysis trompe-loeil``: the paint for the misaligned panel (§4.4)."""
    p = sub.add_parser("trompe-loeil", help="inverse trompe l'oeil: paint for the misaligned panel (§4.4)")
    _add_paint_args(p)
    p.add_argument("--beta", type=float, required=True, help="signed misalignment of panel B, degrees")
    p.add_argument("--lights", required=True, help="light polar angles, degrees, comma-separated")
    p.add_argument(
        "--views",
        help="view polar angles, one per light (default: the normal); --views=-30,0 form for negatives",
    )
    p.add_argument("--objective", choices=OBJECTIVES, default="rms")
    p.add_argument("--at", type=int, default=0, help="geometry index for --objective single")
    p.add_argument(
        "--subset", help="solid | face_L | face_L+travel | face | face+travel | full | names joined by +"
    )
    p.add_argument("--allow-face-darker", action="store_true")
    _add_common(p)
    add_json_flag(p)
    p.set_defaults(handler=_trompe)


def _add_seam(sub: argparse._SubParsersAction) -> None:
    """Add ``station analysis seam``: QA of a seam between two panels."""
    p = sub.add_parser("seam", help="QA of a seam between two panels (design or measurement JSON)")
    p.add_argument(
        "panel_a",
        metavar="PANEL_A",
        help="panel A: a design JSON, a measurement JSON or `station measure --json` output",
    )
    p.add_argument("panel_b", metavar="PANEL_B", help="panel B (the misaligned one), same forms as PANEL_A")
    p.add_argument("--beta", type=float, required=True, help="signed misalignment of panel B, degrees")
    p.add_argument(
        "--lights",
        default=",".join(f"{x:g}" for x in DEFAULT_LIGHTS_DEG),
        help="light angles from the panel normal, degrees, comma-separated (default %(default)s)",
    )
    p.add_argument(
        "--aspecular",
        default=",".join(f"{x:g}" for x in DEFAULT_ASPECULAR_DEG),
        help="aspecular angles judged with every light, degrees, comma-separated (default %(default)s)",
    )
    p.add_argument(
        "--objective",
        choices=("rms", "minimax"),
        default="minimax",
        help="what the corrected paint for panel B minimises over the geometries (default %(default)s)",
    )
    p.add_argument(
        "--illuminant",
        default="D65",
        help="judge the seam under this illuminant, e.g. A or F11 (panels with spectra; default D65)",
    )
    p.add_argument("--png", help="write the report picture here")
    _add_common(p)
    add_json_flag(p)
    p.set_defaults(handler=_seam)


def _add_sweep(sub: argparse._SubParsersAction) -> None:
    """Add ``station analysis sweep``: seam ΔE over view × light × β (Fig. 4.3)."""
    p = sub.add_parser("sweep", help="seam ΔE over view × light × β (thesis Fig. 4.3)")
    _add_paint_args(p)
    p.add_argument("--betas", default="0.5,1,2,3,5,8")
    p.add_argument("--lights", default="15,30,45,60")
    p.add_argument("--views", help="view polar angles (default −80…80 step 2)")
    p.add_argument("--png", help="write the figure here")
    _add_common(p)
    add_json_flag(p)
    p.set_defaults(handler=_sweep)
