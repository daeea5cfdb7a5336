"""Seam ΔE over viewing direction, lighting direction and misalignment (thesis Fig. 4.3).

The thesis reads the goniogeometric index off such curves: the largest β whose curve stays under ε over
the geometries of interest. :func:`seam_sweep` evaluates ΔE on the full grid (β × light × view) in one
vectorised pass; :func:`plot_sweep` draws the figure (docs/misalignment-index.png). The thesis's caption
swaps the light and view symbols (docs/design.md erratum 4); here the axes are labelled by what varies.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from station.analysis.errors import AnalysisInputError
from station.analysis.geometry import Hinge, check_polar
from station.analysis.index import JND_CIE76
from station.analysis.seam_model import SeamModel, check_method

#: Default misalignments of the figure, degrees.
DEFAULT_BETAS_DEG = (0.5, 1.0, 2.0, 3.0, 5.0, 8.0)


@dataclass(frozen=True)
class SweepResult:
    """Seam ΔE on a grid.

    Attributes
    ----------
    betas_deg, lights_deg, views_deg
        Grid axes in degrees (signed β: the rotation direction).
    delta_e
        Seam ΔE, shape (len(betas), len(lights), len(views)); finite everywhere. Entries where panel B
        turns away from the viewer are flagged False in ``visible`` and ignored by the index estimate.
    visible
        Same shape: whether panel B faces the viewer.
    epsilon, method, hinge
        Threshold, ΔE formula and hinge of the sweep.
    """

    betas_deg: NDArray[np.float64]
    lights_deg: NDArray[np.float64]
    views_deg: NDArray[np.float64]
    delta_e: NDArray[np.float64]
    visible: NDArray[np.bool_]
    epsilon: float
    method: str
    hinge: Any

    def index_estimate(self) -> float | None:
        """Graphical index (thesis §4.3.3): the largest β in the sweep whose ΔE stays < ε everywhere."""
        ok = [
            b
            for i, b in enumerate(self.betas_deg)
            if np.all(np.where(self.visible[i], self.delta_e[i], 0.0) < self.epsilon)
        ]
        return float(max(np.abs(ok))) if ok else None

    def to_dict(self) -> dict[str, Any]:
        """JSON-able form."""
        return {
            "betas_deg": self.betas_deg.tolist(),
            "lights_deg": self.lights_deg.tolist(),
            "views_deg": self.views_deg.tolist(),
            "delta_e": np.where(self.visible, self.delta_e, -1.0).tolist(),
            "epsilon": self.epsilon,
            "method": self.method,
            "hinge": self.hinge if isinstance(self.hinge, str) else float(self.hinge),
            "index_estimate_deg": self.index_estimate(),
        }


def seam_sweep(
    paint: Any,
    betas_deg: Sequence[float] = DEFAULT_BETAS_DEG,
    lights_deg: Sequence[float] = (15.0, 30.0, 45.0, 60.0),
    views_deg: Sequence[float] | None = None,
    *,
    hinge: Hinge = "in-plane",
    method: str = "cie76",
    epsilon: float = JND_CIE76,
) -> SweepResult:
    """Seam ΔE for identical paint on both panels over β × light × view (thesis Fig. 4.3).

    Parameters
    ----------
    paint
        ``FaceFlopTravelGloss``.
    betas_deg
        Signed misalignments in degrees (|β| ≤ 45).
    lights_deg, views_deg
        Signed polar angles in degrees; default views −80° … 80° every 2°.
    """
    check_method(method)
    b = np.asarray(list(betas_deg), dtype=float)
    if b.size == 0 or not np.all(np.isfinite(b)) or np.any(np.abs(b) > 45.0):
        raise AnalysisInputError("betas_deg", "one or more finite angles with |β| <= 45", list(betas_deg))
    lights = [check_polar(v, f"lights_deg[{i}]") for i, v in enumerate(lights_deg)]
    views = (
        list(np.arange(-80.0, 80.001, 2.0))
        if views_deg is None
        else [check_polar(v, f"views_deg[{i}]") for i, v in enumerate(views_deg)]
    )
    if not lights or not views:
        raise AnalysisInputError("lights_deg", "at least one light and one view", None)
    ls = [lt for lt in lights for _ in views]
    vs = [v for _ in lights for v in views]
    model = SeamModel(ls, vs, hinge=hinge, method=method)
    de = model.delta_e(paint, paint, b)  # (G, B)
    vis = model.visible(b)
    shape = (len(lights), len(views), len(b))
    de = np.moveaxis(de.reshape(shape), -1, 0)
    vis = np.moveaxis(vis.reshape(shape), -1, 0)
    return SweepResult(
        b, np.asarray(lights), np.asarray(views, dtype=float), de, vis, float(epsilon), method, hinge
    )


def plot_sweep(
    result: SweepResult,
    path: str | Path,
    *,
    light_for_views: float | None = None,
    view_for_lights: float | None = None,
    title: str = "",
) -> Path:
    """Draw Fig. 4.3: ΔE against view (one light) and against light (one view), one curve per β.

    A dashed line marks ε; the legend names each β. Returns the PNG path.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    li = int(np.argmin(np.abs(result.lights_deg - (45.0 if light_for_views is None else light_for_views))))
    vi = int(np.argmin(np.abs(result.views_deg - (0.0 if view_for_lights is None else view_for_lights))))
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2), sharey=True)
    cmap = plt.get_cmap("viridis")
    for i, beta in enumerate(result.betas_deg):
        colour = cmap(i / max(1, len(result.betas_deg) - 1))
        y = np.where(result.visible[i, li], result.delta_e[i, li], np.nan)
        axes[0].plot(result.views_deg, y, color=colour, label=f"β = {beta:g}°")
        axes[1].plot(result.lights_deg, result.delta_e[i, :, vi], "o-", color=colour, ms=3)
    for ax in axes:
        ax.axhline(result.epsilon, ls="--", color="k", lw=1)
        ax.grid(alpha=0.3)
    axes[0].set_xlabel(
        f"view direction (degrees from normal), light at {result.lights_deg[li]:g}° "
        "(aspecular on panel A = view + light)"
    )
    axes[1].set_xlabel(f"light direction (degrees from normal), view at {result.views_deg[vi]:g}°")
    axes[0].set_ylabel(f"seam ΔE ({result.method})")
    axes[0].legend(fontsize=8)
    est = result.index_estimate()
    axes[0].text(
        0.02,
        0.95,
        f"ε = {result.epsilon:g}; largest β under ε everywhere: {'none' if est is None else f'{est:g}°'}",
        transform=axes[0].transAxes,
        fontsize=8,
        va="top",
    )
    fig.suptitle(title or "Seam colour difference against view, light and misalignment (thesis Fig. 4.3)")
    fig.tight_layout()
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
