"""Report pictures made with NumPy and matplotlib only (no renderer import).

* :func:`seam_pair_lab` / :func:`shade_pair`: the two hinged panels side by side under a point light at
  a finite distance (so the shading varies across each panel), colours from
  :func:`station.analysis.shading.point_colour` exposed to panel A's centre, at one of the analysed
  geometries (:func:`geometry_caption` says which); shown in sRGB, darkened by
  :func:`display_exposure` when a paint is brighter than white, so the seam the verdict reports stays
  visible instead of both panels clipping to white.
* :func:`plot_seam_report`: the QA report PNG — panels as painted and corrected, and the BRDF curves
  L*, a*, b* against aspecular angle for paint A, paint B and the corrected paint (thesis Fig. 4.7).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from station.analysis.geometry import Hinge, direction, hinge_azimuth_deg
from station.analysis.shading import point_colour

#: Distance of the point light, in panel half-widths.
LIGHT_DISTANCE = 6.0


def seam_pair_lab(
    paint_a: Any,
    paint_b: Any,
    beta_deg: float,
    light_deg: float,
    view_deg: float,
    hinge: Hinge = "in-plane",
    size: tuple[int, int] = (96, 192),
) -> NDArray[np.float64]:
    """Lab picture (h, w, 3) of panel A (left) and panel B (right, turned by β about the seam).

    Pixels are laid out in panel coordinates (u across the seam, w along it), u ∈ [−1, 1], w ∈ [−½, ½];
    the light is a point at :data:`LIGHT_DISTANCE` in direction *light_deg*, the viewer distant in
    direction *view_deg* (signed polar angles, degrees, :mod:`station.analysis.geometry`). Exposure:
    a white diffuser at panel A's centre is white (L* 100), as the seam model's reference exposure, so
    the columns beside the seam show the model's colours of this geometry (the light's direction there
    is *light_deg*): their ΔE is the seam ΔE :func:`station.analysis.qa.seam_qa` reports. Lab may
    exceed 100 where a paint is brighter than white (an effect paint near the specular direction).
    """
    from station.model.shading import shade_lab

    h, w = size
    az = math.radians(hinge_azimuth_deg(hinge))
    tilt = np.array([math.cos(az), math.sin(az), 0.0])
    axis = np.array([-math.sin(az), math.cos(az), 0.0])
    z = np.array([0.0, 0.0, 1.0])
    b = math.radians(beta_deg)
    t_b = math.cos(b) * tilt - math.sin(b) * z
    n_b = math.sin(b) * tilt + math.cos(b) * z
    u = np.linspace(-1.0, 1.0, w)
    v = np.linspace(-0.5, 0.5, h)
    uu, vv = np.meshgrid(u, v)
    on_b = uu > 0
    pts = np.where(on_b[..., None], uu[..., None] * t_b, uu[..., None] * tilt) + vv[..., None] * axis
    normals = np.where(on_b[..., None], n_b, z)
    light_pos = LIGHT_DISTANCE * direction(light_deg)
    L = light_pos - pts
    L /= np.linalg.norm(L, axis=-1, keepdims=True)
    V = np.broadcast_to(direction(view_deg), L.shape)
    lab = np.where(
        on_b[..., None],
        point_colour(paint_b, L, V, normals, exposure="absolute"),
        point_colour(paint_a, L, V, normals, exposure="absolute"),
    )
    # expose so that a white diffuser at panel A's centre reads white
    k0 = float(np.dot(direction(light_deg), z))
    return np.asarray(shade_lab(lab, 1.0 / k0), dtype=float)


def display_exposure(*labs: NDArray[np.float64], percentile: float = 99.0) -> float:
    """The one display scale (≤ 1) of linear sRGB that fits *labs* below white: 1 unless the
    *percentile* of their largest linear channel exceeds 1 (a paint brighter than white), then its
    inverse. Pictures shown side by side share it, so a difference between them stays visible."""
    from station.model.colorimetry import lab_to_linear_srgb

    peak = max(float(np.percentile(np.max(lab_to_linear_srgb(x), axis=-1), percentile)) for x in labs)
    return 1.0 if peak <= 1.0 else 1.0 / peak


def lab_picture(lab: NDArray[np.float64], exposure: float = 1.0) -> NDArray[np.float64]:
    """Display sRGB (h, w, 3) in [0, 1] of a Lab picture scaled by *exposure* in linear light."""
    from station.model.colorimetry import lab_to_linear_srgb
    from station.model.display import encode_display

    return encode_display(lab_to_linear_srgb(lab) * exposure)


def shade_pair(
    paint_a: Any,
    paint_b: Any,
    beta_deg: float,
    light_deg: float,
    view_deg: float,
    hinge: Hinge = "in-plane",
    size: tuple[int, int] = (96, 192),
    exposure: float = 1.0,
) -> NDArray[np.float64]:
    """sRGB picture (h, w, 3) in [0, 1] of :func:`seam_pair_lab` (display values clipped to [0, 1];
    *exposure* scales linear light first, e.g. :func:`display_exposure`)."""
    return lab_picture(seam_pair_lab(paint_a, paint_b, beta_deg, light_deg, view_deg, hinge, size), exposure)


#: Fig. 4.4's columns: (title, key of :func:`station.analysis.scenarios.solid_panels`; ``None``: paint A).
SOLID_GRID_COLUMNS: tuple[tuple[str, str | None], ...] = (
    ("identical", None),
    ("optimised at 45°", "single_45"),
    ("RMS", "rms"),
    ("per row", "per_geometry"),
)


def draw_solid_grid(
    axes: Any,
    paint: Any,
    panels: Mapping[str, Any],
    lights_deg: Sequence[float],
    beta_deg: float,
    size: tuple[int, int],
) -> None:
    """Fig. 4.4 on a (lights × 4) grid of Matplotlib *axes*: per light (degrees, viewed from the normal)
    the seam of *paint* beside each column's paint B (:data:`SOLID_GRID_COLUMNS`, from the
    ``TrompeResult`` values of *panels*) misaligned by *beta_deg*, its seam ΔE*ab below."""
    for i, light in enumerate(lights_deg):
        for j, (name, key) in enumerate(SOLID_GRID_COLUMNS):
            if key is None:
                pb, de = paint, panels["rms"].seam_de_before[i]
            elif key == "per_geometry":
                pb, de = panels[key].paints[i], panels[key].seam_de_after[i]
            else:
                pb, de = panels[key].paint, panels[key].seam_de_after[i]
            ax = axes[i, j]
            ax.imshow(shade_pair(paint, pb, beta_deg, light, 0.0, size=size))
            ax.set_xticks([])
            ax.set_yticks([])
            ax.set_xlabel(f"ΔE {de:.2f}", fontsize=8)
            if i == 0:
                ax.set_title(name, fontsize=9)
            if j == 0:
                ax.set_ylabel(f"light {light:g}°", fontsize=8)


def geometry_caption(report: Any, g: int) -> str:
    """Which geometry a picture of *report* shows: light, view, aspecular on A and on B, β, seam ΔE."""
    from station.analysis.geometry import rotated_normals
    from station.model.shading import aspecular_deg

    geo = report.geometries[g]
    n_b = rotated_normals(np.array([report.beta_deg]), report.hinge)[0]
    asp_b = float(aspecular_deg(direction(geo.light_deg), direction(geo.view_deg), n_b))
    return (
        f"light {geo.light_deg:g}°, view {geo.view_deg:g}° (aspecular {geo.aspecular_deg:.0f}° on A, "
        f"{asp_b:.0f}° on B), β = {report.beta_deg:+g}°: seam ΔE {report.seam_de[g]:.2f}"
    )


def plot_seam_report(
    report: Any, path: str | Path, *, light_deg: float | None = None, view_deg: float | None = None
) -> Path:
    """Write the QA report PNG (panels as painted / corrected, and the Fig. 4.7 BRDF comparison)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    worst = report.geometries[report.worst]
    lt = worst.light_deg if light_deg is None else light_deg
    vw = worst.view_deg if view_deg is None else view_deg
    corrected = report.correction.paint
    fig = plt.figure(figsize=(12, 6.4))
    gs = fig.add_gridspec(3, 2, width_ratios=(1.15, 1.0))
    ax1 = fig.add_subplot(gs[0:1, 0])
    ax2 = fig.add_subplot(gs[1:2, 0])
    labs = [
        seam_pair_lab(report.paint_a, pb, report.beta_deg, lt, vw, report.hinge)
        for pb in (report.paint_b, corrected)
    ]
    scale = display_exposure(*labs)
    for ax, lab, title in ((ax1, labs[0], "as painted"), (ax2, labs[1], "panel B corrected")):
        ax.imshow(lab_picture(lab, scale), extent=(-1, 1, -0.5, 0.5))
        ax.axvline(0.0, color="w", lw=0.5, alpha=0.5)
        ax.set_title(f"{title}: A | B (β = {report.beta_deg:+g}°, light {lt:g}°, view {vw:g}°)", fontsize=9)
        ax.set_xticks([])
        ax.set_yticks([])
    ax3 = fig.add_subplot(gs[2, 0])
    ax3.axis("off")
    d = report.to_dict()
    lines = [
        f"{'PASS' if report.passed else 'FAIL'}: seam ΔE max {d['seam_de_max']:.2f} "
        f"(tolerance {report.tolerance:g}, {report.method})",
        report.diagnosis,
        f"index β_min = {report.index.beta_min_deg:.3g}°" if report.index.reached else report.index.message,
        f"corrected: worst seam ΔE {report.correction.max_after:.2f}",
    ]
    ax3.text(0.0, 1.0, "\n".join(_wrap(x) for x in lines), va="top", fontsize=8, family="monospace")
    angles = np.linspace(0.0, 110.0, 221)
    labels = ("L*", "a*", "b*")
    for i in range(3):
        ax = fig.add_subplot(gs[i, 1])
        for paint, style, name in (
            (report.paint_a, "-", "A"),
            (report.paint_b, "--", "B"),
            (corrected, ":", "B corrected"),
        ):
            ax.plot(angles, paint.lab_at(angles)[:, i], style, label=name)
        ax.set_ylabel(labels[i])
        ax.grid(alpha=0.3)
        if i == 0:
            ax.legend(fontsize=8)
            ax.set_title("BRDF (Lab) against aspecular angle (thesis Fig. 4.7)", fontsize=9)
        if i == 2:
            ax.set_xlabel("aspecular angle (degrees)")
    fig.tight_layout()
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return path


def _wrap(text: str, width: int = 78) -> str:
    import textwrap

    return "\n".join(textwrap.wrap(text, width)) or text
