"""Data of ColorSnap's 3D Lab-space view (thesis Figs 5.9–5.11): design, matches and a library cloud."""

from __future__ import annotations

import numpy as np

from station.formulate.library import Library
from station.formulate.snap.results import SnapResult

__all__ = ["view_data"]


def view_data(
    library: Library, result: SnapResult, max_cloud: int = 3000, seed: int = 0
) -> dict[str, object]:
    """Data of the 3D Lab-space view (thesis Figs 5.9–5.11): design, matches and a library cloud.

    Returns ``{"angles_deg", "design": [[L,a,b] per angle], "matches": [{"code", "lab"}],
    "cloud": {"lab": [[L,a,b]] at 45°, "codes": [...], "sampled": bool}, "synthetic": bool}``.
    """
    std = library.angle_columns(result.angles_deg)
    rng = np.random.default_rng(seed)
    n = len(library)
    rows = np.sort(rng.choice(n, size=max_cloud, replace=False)) if n > max_cloud else np.arange(n)
    i45 = result.angles_deg.index(45.0) if 45.0 in result.angles_deg else 0
    return {
        "angles_deg": list(result.angles_deg),
        "design": [list(r) for r in result.design_lab],
        "matches": [{"code": m.code, "lab": std[m.index].tolist()} for m in result.matches],
        "cloud": {
            "lab": std[rows, i45].tolist(),
            "codes": library.codes[rows].tolist(),
            "sampled": n > max_cloud,
        },
        "synthetic": library.synthetic,
    }
