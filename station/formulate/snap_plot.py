"""PNG of ColorSnap's 3D Lab-space view (thesis Figs 5.9–5.11): library cloud, design and matches."""

from __future__ import annotations

from pathlib import Path

import numpy as np


def plot_snap_view(view: dict, out: str | Path, title: str = "") -> Path:
    """Render :func:`station.formulate.snap.view_data` output as a 3D scatter PNG (a*, b*, L* axes).

    The library cloud is drawn at 45° in its own sRGB colours (faint); the design's and the best
    match's angle points are joined face → flop so their travel directions can be compared.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from station.model.display import lab_to_display

    out = Path(out)
    cloud = np.asarray(view["cloud"]["lab"], dtype=float).reshape(-1, 3)
    fig = plt.figure(figsize=(7, 6), dpi=110)
    ax = fig.add_subplot(projection="3d")
    if cloud.size:
        rgb = lab_to_display(cloud)
        ax.scatter(
            cloud[:, 1],
            cloud[:, 2],
            cloud[:, 0],
            c=rgb,
            s=4,
            alpha=0.35,
            depthshade=False,
            label="library (45°)" + (" — SYNTHETIC" if view.get("synthetic") else ""),
        )
    design = np.asarray(view["design"], dtype=float)
    ax.plot(design[:, 1], design[:, 2], design[:, 0], "-o", color="black", lw=2, ms=6, label="design 15→110°")
    for i, m in enumerate(view["matches"][:3]):
        lab = np.asarray(m["lab"], dtype=float)
        ax.plot(
            lab[:, 1],
            lab[:, 2],
            lab[:, 0],
            "--s",
            lw=1.5 if i else 2,
            ms=4 if i else 5,
            color=("tab:red", "tab:orange", "tab:olive")[i],
            label=f"match {i + 1}: {m['code']}",
        )
    ax.set_xlabel("a*")
    ax.set_ylabel("b*")
    ax.set_zlabel("L*")
    ax.set_title(title or "ColorSnap: design vs library (Lab, D65/10°)")
    ax.legend(loc="upper left", fontsize=7)
    fig.tight_layout()
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out)
    plt.close(fig)
    return out
