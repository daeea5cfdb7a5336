"""Report pictures made with NumPy and matplotlib only (no renderer import).

* :func:`shade_pair`: the two hinged panels side by side under a point light at a finite distance
  (so the shading varies across each panel), colours from :func:`station.analysis.shading.point_colour`
  exposed to panel A's centre, shown in sRGB (display values clipped to [0, 1] for the picture only).
* :func:`plot_seam_report`: the QA report PNG — panels as painted and corrected, and the BRDF curves
  L*, a*, b* against aspecular angle for paint A, paint B and the corrected paint (thesis Fig. 4.7).
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from station.analysis.geometry import Hinge, direction, hinge_azimuth_deg
from station.analysis.shading import point_colour

#: Distance of the point light, in panel half-widths.
LIGHT_DISTANCE = 6.0


def shade_pair(
    paint_a: Any,
    paint_b: Any,
    beta_deg: float,
    light_deg: float,
    view_deg: float,
    hinge: Hinge = "in-plane",
    size: tuple[int, int] = (96, 192),
) -> NDArray[np.float64]:
    """sRGB picture (h, w, 3) in [0, 1] of panel A (left) and panel B (right, turned by β about the seam).

    Pixels are laid out in panel coordinates (u across the seam, w along it), u ∈ [−1, 1], w ∈ [−½, ½].
    """
    from station.model.colorimetry import lab_to_linear_srgb
    from station.model.display import encode_display

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
    rgb = lab_to_linear_srgb(lab) / k0
    return encode_display(rgb)


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
    for ax, pb, title in ((ax1, report.paint_b, "as painted"), (ax2, corrected, "panel B corrected")):
        img = shade_pair(report.paint_a, pb, report.beta_deg, lt, vw, report.hinge)
        ax.imshow(img, extent=(-1, 1, -0.5, 0.5))
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
