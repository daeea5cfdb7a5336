"""Pictures of designs: L*, a*, b* against aspecular angle, and the a*–b* travel path.

``python -m station.design.plots`` regenerates ``docs/model-curves.png`` from the example designs.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from station.model.angles import ANGLES_6
from station.model.display import lab_to_display
from station.model.representations import FaceFlopTravelGloss


def _swatch_rgb(design: FaceFlopTravelGloss) -> np.ndarray:
    """Display colour of the design at 45° (sRGB-encoded, clipped for the legend only)."""
    return lab_to_display(design.lab_at(45.0))


def plot_designs(designs: Sequence[FaceFlopTravelGloss], out: str | Path) -> Path:
    """Write a PNG with L*, a*, b* against aspecular angle (−15…130°) and the a*–b* path of each design.

    Measured-angle markers sit at the 6-angle set −15/15/25/45/75/110°; the travel angle θ_clamp is marked on the L* plot.
    """
    theta = np.linspace(-15.0, 130.0, 291)
    fig = Figure(figsize=(16, 4.2), layout="constrained")  # no pyplot: no backend switched, no global state
    axes = fig.subplots(1, 4)
    for i, d in enumerate(designs):
        lab = d.lab_at(theta)
        pts = d.lab_at(np.asarray(ANGLES_6))
        colour = (
            _swatch_rgb(d)
            if np.ptp(_swatch_rgb(d)) > 0.05 or _swatch_rgb(d).mean() < 0.85
            else (0.4, 0.4, 0.4)
        )
        label = d.name or f"design {i + 1}"
        for ch in range(3):
            axes[ch].plot(theta, lab[:, ch], color=colour, lw=2, label=label)
            axes[ch].plot(ANGLES_6, pts[:, ch], "o", color=colour, ms=4)
        if d.travel_deg is not None:
            axes[0].axvline(d.travel_deg, color=colour, ls=":", lw=1)
        axes[3].plot(lab[:, 1], lab[:, 2], color=colour, lw=2)
        axes[3].annotate(
            "", xy=d.face[1:], xytext=d.flop[1:], arrowprops={"arrowstyle": "->", "color": colour}
        )
    for ax, name in zip(axes[:3], ("L*", "a*", "b*"), strict=True):
        ax.set_xlabel("aspecular angle (°)")
        ax.set_ylabel(name)
        ax.axvline(15, color="0.8", lw=0.8)
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=8)
    axes[0].set_title("L* (dotted: travel θ_clamp)")
    axes[3].set_xlabel("a*")
    axes[3].set_ylabel("b*")
    axes[3].set_title("a*–b*: flop → face")
    axes[3].axhline(0, color="0.8", lw=0.8)
    axes[3].axvline(0, color="0.8", lw=0.8)
    axes[3].set_aspect("equal", adjustable="datalim")
    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=110)
    return out


if __name__ == "__main__":
    from station.model.examples import EXAMPLES

    print(
        plot_designs(
            list(EXAMPLES.values()), Path(__file__).resolve().parents[2] / "docs" / "model-curves.png"
        )
    )
