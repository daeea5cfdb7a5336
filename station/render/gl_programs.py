"""Programs of :class:`station.render.gl_renderer.GLRenderer`: the ``#define`` set of
``shaders/render.frag.glsl`` (what a renderer fixes once, what a frame's features compile in) and the
upload of a frame's uniforms to a program.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from station.render.flakes import CELL_PIXELS, GLINT_RADIUS, WINDOW_NORM, flake_tint
from station.render.horizon_poly import HORIZON_DEGREE
from station.render.lobes import COSINE_SG_SHARPNESS
from station.render.prefilter import WIDE_EXPONENT
from station.render.shapes import SHAPE_INDEX
from station.render.stage import PENUMBRA_DEG
from station.render.tonemap import SRGB_POLY, SRGB_T_OFFSET, SRGB_T_SCALE

#: The program kinds of a mesh, by the shader's MESH_PARTS: all its triangles, the paint's, the neutral parts'.
MESH_KINDS = ("mesh", "mesh-paint", "mesh-parts")


def renderer_defines(
    *,
    n_lobes: int,
    diffuse: str,
    combined: bool,
    horizon: str,
    horizon_n: int,
    atlas_face: int,
    diffuse_face: int,
    n_wide: int,
    n_lights: int,
    bound_exponents: np.ndarray,
    horizon_cheb: tuple[np.ndarray, int],
) -> dict[str, object]:
    """The defines a renderer fixes for all its programs. The lights and exponents are compiled in as
    constants, so the lobe and light loops unroll with constant indices (llvmpipe gathers a uniform
    array indexed by a loop counter per pixel); so are the wide lobes' Chebyshev polynomials of g
    (*horizon_cheb*: coefficients (m, HORIZON_DEGREE + 1) and the mask of the lobes using them,
    :func:`station.render.horizon_poly.horizon_chebyshev`)."""
    from station.render.meshes import NEUTRAL_ALBEDO

    return {
        "NEUTRAL_ALBEDO": f"{NEUTRAL_ALBEDO:.4f}",
        "PENUMBRA_DEG": f"{PENUMBRA_DEG:.4f}",
        "FLAKE_CELL_PIXELS": f"{CELL_PIXELS:.4f}",
        "FLAKE_GLINT_RADIUS": f"{GLINT_RADIUS:.6f}",
        "FLAKE_WINDOW_NORM": f"{WINDOW_NORM:.6f}",
        "N_LOBES": n_lobes,
        "DIFFUSE_SH": int(diffuse == "sh"),
        "COMBINED": int(combined),
        "HORIZON_N": horizon_n,
        "ATLAS_FACE": atlas_face,
        "DIFFUSE_FACE": diffuse_face,
        "N_WIDE": n_wide,
        "MAX_LIGHTS": max(1, n_lights),
        "N_LIGHTS": n_lights,
        "LOBE_EXPONENTS": ", ".join(f"{float(e):.9g}" for e in bound_exponents),
        "WIDE_EXPONENT": f"{WIDE_EXPONENT:.1f}",
        "BENT_DD": int(horizon == "lut"),
        "COSINE_SG": f"{COSINE_SG_SHARPNESS:.4f}",
        "HORIZON_DEGREE": HORIZON_DEGREE,
        "HORIZON_CHEB_MASK": horizon_cheb[1],
        "HORIZON_CHEB": ", ".join(f"{float(v):.9g}" for v in np.asarray(horizon_cheb[0]).ravel()),
        **srgb_defines(),
    }


def srgb_defines() -> dict[str, object]:
    """The defines of ``shaders/tonemap.glsl``'s sRGB encoding: its polynomial
    (:data:`station.render.tonemap.SRGB_POLY`) and the map from x^(1/16) to the polynomial's variable."""
    return {
        "SRGB_T_SCALE": repr(SRGB_T_SCALE),
        "SRGB_T_OFFSET": repr(SRGB_T_OFFSET),
        "SRGB_POLY": ", ".join(repr(c) for c in SRGB_POLY),
    }


def frame_defines(
    shape: str,
    linear: bool,
    kind: str,
    features: tuple[int, ...],
    terms: tuple[int, int, int],
    n_occ: int,
    curve: int,
) -> dict[str, object]:
    """The defines of one program kind: a ray-cast *shape* (kind "shape"; "footprint" over its screen
    polygon, "inside" over the part of it where every ray hits, "inside-smooth" the same reading the smooth
    terms that "coarse" drew at a coarser rate), the stage alone ("stage"; "backdrop" around a shape's
    polygon), the ground bake ("ground") or a mesh (MESH_KINDS); *features* = (coat, stage bits, flakes[, anisotropy]) (the
    stage's bits: 1 a stage, 2 its backdrop, 4 its ground, 8 the backdrop lobe's lights); *terms* = (bit
    mask of the wide lobes with a gloss weight, a narrow directionally diffuse weight, the aspecular
    fall-off); *n_occ*: the ground's sphere occluders; *curve*: the tone curve's index (8-bit output)."""
    return {
        "SHAPE": SHAPE_INDEX[shape],
        "MESH": int(kind in MESH_KINDS),
        "MESH_PARTS": MESH_KINDS.index(kind) if kind in MESH_KINDS else 0,
        "NO_SHAPE": int(kind in ("stage", "ground", "backdrop")),
        "INSIDE_SHAPE": int(kind in ("inside", "inside-smooth")),
        "SMOOTH_OUT": int(kind == "coarse"),
        "SMOOTH_IN": int(kind == "inside-smooth"),
        "BAKE_GROUND": int(kind == "ground"),
        "WIDE_GLOSS_MASK": terms[0],
        "NARROW_DD": terms[1],
        "HAS_FALL_OFF": terms[2],
        "N_OCC": n_occ,
        "CURVE": curve,
        "HAS_COAT": features[0],
        "HAS_STAGE": int(features[1] != 0),
        "STAGE_BACKDROP": features[1] >> 1 & 1,
        "STAGE_GROUND": features[1] >> 2 & 1,
        "BACKDROP_LIGHTS": features[1] >> 3 & 1,
        "HAS_FLAKES": features[2],
        **({"HAS_ANISO": 1} if len(features) > 3 and features[3] else {}),
        "OUTPUT_LINEAR": int(linear),
    }


def _has(prog: Any, name: str) -> bool:
    """Whether *prog* has the uniform *name* (a dict lookup: ``name in prog`` walks every member)."""
    return prog.get(name, None) is not None


def _write(prog: Any, name: str, values: Any) -> None:
    prog[name].write(np.asarray(values, np.float32).tobytes())


def set_uniforms(
    prog: Any,
    uniforms: dict,
    mw: list,
    occ: np.ndarray,
    m: int,
    *,
    combined: bool,
    lights: Any,
    sh: np.ndarray,
) -> None:
    """Upload a frame's *uniforms* (scalars by name; ``_``-prefixed entries are arrays) and the paints'
    bound weights *mw* (w_D, w_DD, w_G per paint) to *prog*, skipping what its compiler dropped; *m*: the
    lobe count (texture units of the atlases follow the lobes); *occ*: the sphere occluders (k, 4)."""
    for name, value in uniforms.items():
        if _has(prog, name):
            prog[name].value = value
    if _has(prog, "u_wd"):
        _write(prog, "u_wd", [w[0] for w in mw])
    if combined:
        for unit, name in enumerate(("u_gloss", "u_dd")):
            if _has(prog, name):
                prog[name].value = m + unit
    # The compiler trims uniform arrays to the entries the shader can reach (N_WIDE when combined).
    if _has(prog, "u_lobes"):
        n = prog["u_lobes"].array_length
        prog["u_lobes"].value = list(range(n)) if n > 1 else 0
    if lights is not None and lights.count:  # the compiler drops what a program never reads
        for name, values in (
            ("u_light_dir", lights.directions),
            ("u_light_flux", lights.flux),
            ("u_light_spread", lights.spreads()),
        ):
            if _has(prog, name):
                _write(prog, name, values)
        if _has(
            prog, "u_light_world"
        ):  # world directions: u_rot (column-major R, environment <- world) undone
            rot = np.asarray(uniforms["u_rot"], dtype=np.float64).reshape(3, 3).T
            _write(prog, "u_light_world", np.asarray(lights.directions, dtype=np.float64) @ rot)
    for name, part in (("u_wdd", 1), ("u_wg", 2)):
        if _has(prog, name):
            _write(prog, name, np.concatenate([w[part] for w in mw])[: prog[name].array_length])
    if _has(prog, "u_aniso_w"):
        _write(prog, "u_aniso_w", uniforms["_aniso_w"])
        _write(prog, "u_aniso_ps", uniforms["_aniso_ps"])
    if _has(prog, "u_flake_tint"):
        _write(prog, "u_flake_tint", [flake_tint(w[1]) for w in mw])
    if _has(prog, "u_wa"):
        _write(prog, "u_wa", uniforms["_wa"])
    if _has(prog, "u_wk"):
        _write(prog, "u_wk", uniforms["_wk"])
    if _has(prog, "u_sh_coat"):
        prog["u_sh_coat"].write(uniforms["_sh_coat"].tobytes())
    if _has(prog, "u_occ"):
        prog["u_occ"].write(occ[: prog["u_occ"].array_length].tobytes())
    if _has(prog, "u_sh"):
        prog["u_sh"].write(sh.tobytes())
    for name in (  # station.render.gl_shadows.ShadowMaps.bind
        "u_shadow_mat",
        "u_shadow_par",
        "u_shadow_c",
        "u_shadow_disc_mat",
        "u_shadow_disc_par",
    ):
        if _has(prog, name):
            _write(prog, name, uniforms["_" + name[2:]][: prog[name].array_length])
    for name in (
        "u_shadow_cmp",
        "u_shadow_raw",
        "u_shadow_esm",
        "u_shadow_disc",
        "u_shadowed_gloss",  # station.render.gl_light_maps.ShadowedMaps.bind
        "u_shadowed_dd",
        "u_shadowed_glint",
        "u_shadowed_mean",
    ):
        if _has(prog, name):
            units = uniforms["_" + name[2:]][: prog[name].array_length]
            prog[name].value = units if len(units) > 1 else units[0]


def binding_order(
    basis: Any, horizon: str, horizon_max_exponent: float
) -> tuple[np.ndarray, np.ndarray, Any]:
    """(wide flag per basis lobe (int32), binding order, the lights the wide lobes took out or None):
    wide lobes (horizon table below *horizon_max_exponent*, or lights taken out of them) bind first, so
    the shader loops over a prefix."""
    has_lights = basis.lights is not None and any(basis.wide)
    wide = [
        int((horizon != "none" and e < horizon_max_exponent) or (has_lights and basis.wide[i]))
        for i, e in enumerate(basis.exponents)
    ]
    order = [i for i in range(len(wide)) if wide[i]] + [i for i in range(len(wide)) if not wide[i]]
    return np.array(wide, np.int32), np.array(order), basis.lights if has_lights else None


def compiled_terms(mw: list, wide_bound: np.ndarray) -> tuple[int, int]:
    """(bit i set when bound wide lobe i has a gloss weight in either paint, 1 when a narrow lobe has a
    directionally diffuse weight) of the bound weights *mw*: a term whose weights are all exactly zero
    adds nothing, so its lookups are compiled out (a typical effect paint has its gloss in the narrow
    lobes and its colour travel in the wide ones: 3 of 8 lookups)."""
    wide = wide_bound != 0
    mask = 0
    for i in np.nonzero(wide)[0]:
        if any(w[2][i] > 0.0 for w in mw):
            mask |= 1 << int(i)
    return mask, int(any(np.any(w[1][~wide] > 0.0) for w in mw))
