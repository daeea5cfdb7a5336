"""``station design …``: colour styling tools from the command line (thesis §3.4–§3.7).

* ``variations`` — the ring of variations of a design (face | flop | travel-gloss, a degree).
* ``eyedrop`` — face/flop(/gloss) eyedroppers on an image → a design.
* ``render`` — a design in a built-in scene as a PNG (the initial image an artist paints over, §3.7.1).
* ``palette`` — the palette swatch and the booklet thumbnail as PNGs.
* ``sketch-fit`` — fit a design to concept art painted over a built-in scene; JSON
  ``{"design", "rms_de", "failed", "seconds", ...}``. With ``--environment studio|HDR`` the art is
  environment-lit (thesis §3.7.5): the sphere under the 16 studio lights, or under an .hdr/.exr
  environment cut into ``--lights`` directional lights, fitted through per-lobe basis images
  (``station.design.sketch.fit_environment``); ``render --environment`` draws the image to paint over.
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from station.cli._common import add_design_args, add_json_flag, design_from_args, parse_floats
from station.design.options import CATEGORIES, GLOSS_MODES, SCENE_NAMES
from station.errors import InputError

if TYPE_CHECKING:
    from station.design.scene import EnvironmentScene
    from station.model import FaceFlopTravelGloss


def _default_silver() -> FaceFlopTravelGloss:
    """The thesis's default starting colour for a sketch (§3.7.1: "The system's default is silver")."""
    from station.model import FaceFlopTravelGloss

    return FaceFlopTravelGloss((85.0, 0.0, 0.0), (40.0, 0.0, 0.0), 70.0, 50.0, "silver")


#: Directional lights an environment map is cut into by default (the studio environment's count).
DEFAULT_LIGHTS = 16
STUDIO = "studio"


def _hdr_lights(path: Path, count: int) -> tuple[np.ndarray, np.ndarray]:
    """Cut an equirectangular .hdr/.exr into about *count* directional lights (latitude-longitude cells).

    The map is split into r × 2r cells (r = round(√(count/2)), at least 1 × 2); each cell becomes one
    light at its luminous-flux-weighted mean direction with RGB flux Σ radiance × solid angle (so a
    lobe integrates it as flux · lobe(direction)). The fluxes are then scaled so that the brightest
    point of a white diffuse sphere in the view reads 1 (the exposure: the map's absolute scale is
    arbitrary).
    """
    from station.design.scene import sphere_scene
    from station.model.colorimetry import REC709_LUMINANCE
    from station.render.cubemap import equirect_directions, equirect_solid_angles
    from station.render.environment import load_environment

    if not path.is_file():
        raise InputError("environment", f"'{STUDIO}' or an existing .hdr/.exr file", str(path))
    img = np.asarray(load_environment(path).equirect, dtype=float)
    h, w = img.shape[:2]
    rows = max(1, round(math.sqrt(count / 2.0)))
    cell = (np.arange(h) * rows // h)[:, None] * (2 * rows) + (np.arange(w) * 2 * rows // w)[None, :]
    flux_px = img * equirect_solid_angles(h, w)[..., None]
    lum_px = flux_px @ REC709_LUMINANCE
    dirs_px = equirect_directions(h, w)
    size = 2 * rows * rows
    flat = cell.ravel()
    flux = np.stack([np.bincount(flat, flux_px[..., c].ravel(), size) for c in range(3)], -1)
    vec = np.stack([np.bincount(flat, (lum_px * dirs_px[..., c]).ravel(), size) for c in range(3)], -1)
    norm = np.linalg.norm(vec, axis=1)
    keep = norm > 0.0
    dirs, flux = vec[keep] / norm[keep, None], flux[keep]
    if not len(dirs):
        raise InputError("environment", "an environment with some light in it", str(path))
    base = sphere_scene(32)
    lit = np.clip(base.normals[base.mask] @ dirs.T, 0.0, None) @ (flux @ REC709_LUMINANCE)
    return dirs, flux / max(float(lit.max()), 1e-12)


def _environment_scene(spec: str, size: int, lights: int) -> EnvironmentScene:
    """The sphere of *size* pixels under the studio lights or under the lights of an HDR file."""
    from station.design.scene import (
        EnvironmentScene,
        aspecular_and_lambert,
        environment_sphere_scene,
        sphere_scene,
    )

    if not 1 <= lights <= 512:
        raise InputError("lights", "1 <= lights <= 512", lights)
    if spec == STUDIO:
        return environment_sphere_scene(size, lights)
    path = Path(spec)
    dirs, rgb = _hdr_lights(path, lights)
    base = sphere_scene(size)
    thetas, phis = zip(*(aspecular_and_lambert(base.normals, base.mask, d) for d in dirs), strict=True)
    return EnvironmentScene(
        f"sphere-{path.stem}", base.mask, dirs, rgb, np.stack(thetas), np.stack(phis), base.normals
    )


def _xy(text: str, field: str) -> tuple[float, float]:
    x, y = parse_floats(text, field, 2)
    return (x, y)


def _variations(args: argparse.Namespace) -> dict[str, Any]:
    from station.design.variations import variations

    ring = variations(design_from_args(args), args.degree, args.category)
    return ring.to_dict()


def _eyedrop(args: argparse.Namespace) -> dict[str, Any]:
    from station.design.images import load_image
    from station.design.moodboard import eyedrop_design

    img = load_image(args.image)
    face, flop = _xy(args.face, "face"), _xy(args.flop, "flop")
    r = eyedrop_design(
        img.pixels,
        face,
        flop,
        travel_deg=args.travel,
        gloss_gu=args.gloss_gu,
        radius=args.radius,
        auto_swap=not args.no_swap,
        gloss_xy=None if args.gloss is None else _xy(args.gloss, "gloss"),
    )
    return r.to_dict(colour=img.colour_note)


def _render(args: argparse.Namespace) -> dict[str, Any]:
    from station.design.images import save_png
    from station.design.scene import builtin_scene, shade, shade_environment, srgb_encode
    from station.model.design_io import design_to_dict

    design = design_from_args(args) if (args.design or args.face) else _default_silver()
    if args.environment is not None:
        if args.scene is not None:
            raise InputError(
                "scene", "no --scene with --environment (the environment lights a sphere)", args.scene
            )
        env = _environment_scene(args.environment, args.size, args.lights)
        path = save_png(args.out, srgb_encode(shade_environment(env, design)))
        name = env.name
    else:
        name = args.scene or "sphere-point"
        path = save_png(args.out, srgb_encode(shade(builtin_scene(name, args.size), design)))
    return {"path": str(path), "scene": name, "size": args.size, "design": design_to_dict(design)}


def _palette(args: argparse.Namespace) -> dict[str, Any]:
    from station.design.images import save_png
    from station.design.palette import booklet, swatch

    design = design_from_args(args)
    out = Path(args.out)
    sw = swatch(design)
    p1 = save_png(out.with_name(out.stem + "-swatch.png"), sw.pixels)
    p2 = save_png(out.with_name(out.stem + "-booklet.png"), booklet(design))
    return {"swatch": str(p1), "booklet": str(p2), "out_of_gamut_columns": sw.out_of_gamut_columns}


def _sketch_fit(args: argparse.Namespace) -> dict[str, Any]:
    from station.design.images import load_image
    from station.design.scene import builtin_scene, shade, srgb_encode
    from station.design.sketch import fit_point_light

    art = load_image(args.art).pixels
    h, w = art.shape[:2]
    if h != w:
        raise InputError(
            "art",
            "a square image the size of the scene (render one with `station design render`)",
            f"{w}x{h}",
        )
    if args.environment is not None:
        return _environment_fit(args, art)
    if args.gloss_gu is not None:
        raise InputError(
            "gloss_gu", "only with --environment (a point-lit fit reads --gloss-mode)", args.gloss_gu
        )
    scene = builtin_scene(args.scene or "sphere-point", h)
    initial = (
        load_image(args.initial).pixels if args.initial else srgb_encode(shade(scene, _default_silver()))
    )
    fit = fit_point_light(scene, art, initial, gloss=args.gloss_mode or "highlight")
    return fit.to_dict()


def _environment_fit(args: argparse.Namespace, art: np.ndarray) -> dict[str, Any]:
    """The environment-lit fit (§3.7.5): basis images of the sphere in the environment, then NNLS."""
    import time

    from station.design.images import load_image
    from station.design.scene import lobe_basis, shade_environment, srgb_encode
    from station.design.sketch import fit_environment
    from station.model.domain import DEFAULT_GLOSS_GU, check_gloss

    for name, value in (("scene", args.scene), ("gloss_mode", args.gloss_mode)):
        if value is not None:
            raise InputError(
                name, "not with --environment (the environment fit lights a sphere, gloss --gloss-gu)", value
            )
    gloss = DEFAULT_GLOSS_GU if args.gloss_gu is None else float(check_gloss(args.gloss_gu) or 0.0)
    env = _environment_scene(args.environment, art.shape[0], args.lights)
    t0 = time.perf_counter()
    basis = lobe_basis(env)
    basis_s = time.perf_counter() - t0
    initial = (
        load_image(args.initial).pixels
        if args.initial
        else srgb_encode(shade_environment(env, _default_silver()))
    )
    source = "the studio" if args.environment == STUDIO else Path(args.environment).name
    lighting = f"{len(env.light_dirs)} point lights from {source}"  # the map discretised into lights
    fit = fit_environment(basis, art, initial, gloss_gu=gloss, lighting=lighting)
    out = fit.to_dict()
    out.update(environment=env.name, lights=len(env.light_dirs), basis_seconds=basis_s)
    return out


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add ``station design …`` to the top-level parser."""
    top = subparsers.add_parser("design", help="colour styling tools (variations, eyedroppers, sketch fit)")
    sub = top.add_subparsers(dest="design_command", required=True, metavar="TOOL")

    p = sub.add_parser("variations", help="ring of variations of a design (thesis §3.4.4)")
    add_design_args(p)
    p.add_argument(
        "--degree",
        type=float,
        default=5.0,
        help="step: ΔE*ab for colours, degrees for travel, GU for gloss (0 < d <= 50; default 5)",
    )
    p.add_argument("--category", choices=CATEGORIES, default="face")
    add_json_flag(p)
    p.set_defaults(handler=_variations)

    p = sub.add_parser("eyedrop", help="seed a design from an image with the eyedroppers (thesis §3.5)")
    p.add_argument("image", help="PNG or JPEG")
    p.add_argument("--face", required=True, help="face eyedropper pixel X,Y")
    p.add_argument("--flop", required=True, help="flop eyedropper pixel X,Y")
    p.add_argument("--gloss", help="gloss eyedropper pixel X,Y (contrast gloss); default --gloss-gu")
    p.add_argument("--gloss-gu", type=float, default=50.0, help="gloss without the gloss eyedropper (GU)")
    p.add_argument("--travel", type=float, default=75.0, help="travel slider, degrees (default 75)")
    p.add_argument("--radius", type=int, default=3, help="eyedropper radius in pixels (default 3)")
    p.add_argument(
        "--no-swap", action="store_true", help="keep a face darker than the flop (retroreflective)"
    )
    add_json_flag(p)
    p.set_defaults(handler=_eyedrop)

    p = sub.add_parser("render", help="render a design (default silver) in a built-in scene to PNG")
    add_design_args(p)
    p.add_argument("--scene", choices=SCENE_NAMES, help="point-lit scene (default sphere-point)")
    _add_environment_args(p)
    p.add_argument("--size", type=int, default=128, help="image size in pixels (square)")
    p.add_argument("--out", required=True, help="PNG to write")
    add_json_flag(p)
    p.set_defaults(handler=_render)

    p = sub.add_parser("palette", help="palette swatch and booklet thumbnail PNGs (thesis §3.4.6)")
    add_design_args(p)
    p.add_argument("--out", required=True, help="base path: writes BASE-swatch.png and BASE-booklet.png")
    add_json_flag(p)
    p.set_defaults(handler=_palette)

    p = sub.add_parser(
        "sketch-fit",
        help="fit a design to concept art over a built-in scene or an environment (thesis §3.7)",
        description=(
            "Fit a design to the art an artist painted over a rendering. Point-lit (default): the "
            "scene is --scene and the gloss is read from the art's highlight (--gloss-mode). "
            "Environment-lit (--environment studio or an .hdr/.exr file): the art was painted over "
            "`station design render --environment` of the same map; the fit takes milliseconds once "
            "the basis images are built (the thesis's search took several minutes)."
        ),
    )
    p.add_argument("--scene", choices=SCENE_NAMES, help="point-lit scene (default sphere-point)")
    p.add_argument("--art", required=True, help="the artist's image (PNG/JPEG, the scene's size)")
    p.add_argument("--initial", help="the image the artist started from (default: the scene in silver)")
    p.add_argument(
        "--gloss-mode",
        choices=GLOSS_MODES,
        help="point-lit gloss: read off the art's highlight (default), the thesis's contrast gloss, "
        "50 GU, or fitted with the colour",
    )
    p.add_argument("--gloss-gu", type=float, help="gloss of the environment-lit fit in GU (default 50)")
    _add_environment_args(p)
    add_json_flag(p)
    p.set_defaults(handler=_sketch_fit)


def _add_environment_args(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--environment",
        metavar="studio|HDR",
        help="light a sphere by the 16 studio lights ('studio') or by an .hdr/.exr environment file",
    )
    p.add_argument(
        "--lights",
        type=int,
        default=DEFAULT_LIGHTS,
        help=f"directional lights the environment is cut into (default {DEFAULT_LIGHTS})",
    )
