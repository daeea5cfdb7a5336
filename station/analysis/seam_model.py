"""The seam colour difference, vectorised over geometries: panel A against panel B rotated by β.

:class:`SeamModel` evaluates ΔE(c(f, Ω, Ψ), c(f, Ω_β, Ψ_β)) of thesis eq 4.3.1 for a set of geometries
(a point light and a view, or a view under an environment); the index (:mod:`station.analysis.index`),
the sweep and the inverse trompe l'oeil are built on it. Colours ``c`` are defined in
:mod:`station.analysis.shading`, the geometry in :mod:`station.analysis.geometry`.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from station.analysis.errors import AnalysisInputError
from station.analysis.geometry import Hinge, direction, hinge_azimuth_deg, rotated_normals
from station.analysis.shading import Environment, Exposure, environment_colour, point_colour
from station.model.difference import delta_e
from station.model.domain import DELTA_E_COMPUTED, DELTA_E_ENVIRONMENT
from station.model.shading import aspecular_deg

if TYPE_CHECKING:
    from station.model import FaceFlopTravelGloss

#: ΔE formulas accepted (station.model.difference.delta_e).
DE_METHODS = DELTA_E_COMPUTED


def check_method(method: str) -> str:
    """Validate a ΔE formula name."""
    if method not in DE_METHODS:
        raise AnalysisInputError("method", " | ".join(DE_METHODS), method)
    return method


class SeamModel:
    """Vectorised seam ΔE for a set of geometries: panel A (+z) against panel B rotated by β.

    Rows are geometries (a light/view pair, or a view under an environment). Used by the index, the
    sweep and the inverse trompe l'oeil.
    """

    def __init__(
        self,
        lights: list[float] | Environment,
        views: list[float],
        *,
        hinge: Hinge = "in-plane",
        method: str = "cie76",
        exposure: Exposure = "reference",
        gloss: bool = False,
    ) -> None:
        self.method = check_method(method)
        hinge_azimuth_deg(hinge)
        self.hinge = hinge
        self.exposure = exposure
        if exposure not in ("reference", "absolute"):
            raise AnalysisInputError("exposure", '"reference" or "absolute"', exposure)
        self.gloss = gloss
        self.env = lights if isinstance(lights, Environment) else None
        if not isinstance(lights, Environment):
            if len(lights) != len(views):
                raise AnalysisInputError("views", f"{len(lights)} view angles (one per light)", len(views))
            self.light_deg = np.asarray(lights, dtype=float)
            self.L = direction(self.light_deg)[:, None, :]  # (G, 1, 3)
        else:
            self.light_deg = np.full(len(views), np.nan)
        self.view_deg = np.asarray(views, dtype=float)
        self.V = direction(self.view_deg)[:, None, :]  # (G, 1, 3)
        self._alpha = self._din_angles() if self.method == "din6175" else None
        self._ref_cache: tuple[int, object, NDArray[np.float64]] | None = None

    def _din_angles(self) -> NDArray[np.float64]:
        """Aspecular angle of each geometry on panel A (degrees, (G,)): the angle DIN 6175-2 weighs by."""
        if self.env is not None:
            raise AnalysisInputError(
                "method",
                f"{' | '.join(DELTA_E_ENVIRONMENT)} under an environment (din6175 weighs by the aspecular angle "
                "of a point light)",
                self.method,
            )
        alpha = aspecular_deg(self.L[:, 0], self.V[:, 0], np.array([0.0, 0.0, 1.0]))
        if np.any(alpha <= 0.0):
            raise AnalysisInputError(
                "views",
                "geometries off the specular direction for din6175 (aspecular > 0)",
                self.view_deg.tolist(),
            )
        return alpha

    @property
    def size(self) -> int:
        """Number of geometries (rows)."""
        return len(self.view_deg)

    def colour(
        self, paint: FaceFlopTravelGloss, normals: NDArray[np.float64], rows: NDArray[np.intp] | None = None
    ) -> NDArray[np.float64]:
        """Lab of *paint* on panels with *normals* (B, 3) for each geometry row → (G, B, 3)."""
        rows = np.arange(self.size) if rows is None else rows
        V = self.V[rows]
        if self.env is None:
            return point_colour(
                paint, self.L[rows], V, normals[None, :, :], exposure=self.exposure, gloss=self.gloss
            )
        out = np.empty((len(rows), len(normals), 3))
        for i, r in enumerate(rows):
            out[i] = environment_colour(paint, self.env, self.V[r, 0], normals, gloss=self.gloss)
        return out

    def reference(
        self, paint: FaceFlopTravelGloss, rows: NDArray[np.intp] | None = None
    ) -> NDArray[np.float64]:
        """Lab of *paint* on panel A for each geometry row → (G, 1, 3)."""
        return self.colour(paint, np.array([[0.0, 0.0, 1.0]]), rows)

    def delta_e(
        self,
        paint_a: FaceFlopTravelGloss,
        paint_b: FaceFlopTravelGloss,
        beta_deg: NDArray[np.float64],
        rows: NDArray[np.intp] | None = None,
    ) -> NDArray[np.float64]:
        """Seam ΔE (G, B): paint A on panel A against paint B on panel B rotated by each β (degrees)."""
        beta = np.asarray(beta_deg, dtype=float).reshape(-1)
        normals = rotated_normals(beta, self.hinge)
        ca = self._reference_cached(paint_a, rows)
        cb = self._unrotated_is_reference(
            paint_a, paint_b, ca, beta, self.colour(paint_b, normals, rows), rows
        )
        return self.difference(ca, cb, rows)

    def _unrotated_is_reference(
        self,
        paint_a: FaceFlopTravelGloss,
        paint_b: FaceFlopTravelGloss,
        ca: NDArray[np.float64],
        beta: NDArray[np.float64],
        cb: NDArray[np.float64],
        rows: NDArray[np.intp] | None,
    ) -> NDArray[np.float64]:
        """Panel B's colours *cb* (…, B, 3) with every β = 0 entry replaced by panel A's colour of *paint_b*.

        At β = 0 panel B is panel A (same normal, eq 4.3.1 with Ω_0 = Ω), so its colour is taken from the
        one reference evaluation rather than computed again in a batch of another size: the same paint
        then gives ΔE(0) = 0 exactly. Computed twice, the two Lab values may differ by a rounding step of
        the linear-sRGB matrix product that depends on the batch size and the NumPy build; at the
        L* ≈ 1e16 of a travel just above 15° seen near specular (the quadratic's extrapolation, eq 3.3.2)
        one step of f(Y) ≈ 1e14 is 2 in L* and 7.8 in a*, i.e. a spurious ΔE of about 9 at β = 0.
        """
        zero = beta == 0.0
        if not np.any(zero):
            return cb
        ref_b = ca if paint_b is paint_a else self.reference(paint_b)
        if paint_b is not paint_a and rows is not None:
            ref_b = ref_b[rows]  # all rows at once, as panel A's colour is evaluated
        return np.where(zero[..., None], ref_b, cb)

    def difference(
        self, lab_a: NDArray[np.float64], lab_b: NDArray[np.float64], rows: NDArray[np.intp] | None = None
    ) -> NDArray[np.float64]:
        """ΔE with this model's formula (reference first), (G, B) for the geometry *rows* (all by default);
        CIE76 is computed inline (same numbers). DIN 6175-2 weighs each row by its aspecular angle on panel A."""
        lab_a = np.broadcast_to(lab_a, lab_b.shape)
        if self.method == "cie76":
            d = lab_b - lab_a
            return np.sqrt(np.einsum("...i,...i->...", d, d))
        alpha = None
        if self._alpha is not None:
            per_row = self._alpha if rows is None else self._alpha[rows]
            alpha = np.broadcast_to(per_row.reshape(-1, *([1] * (lab_b.ndim - 2))), lab_b.shape[:-1])
        return np.asarray(delta_e(lab_a, lab_b, method=self.method, aspecular_deg=alpha), dtype=float)

    def _reference_cached(
        self, paint: FaceFlopTravelGloss, rows: NDArray[np.intp] | None
    ) -> NDArray[np.float64]:
        key = id(paint)
        cache = self._ref_cache
        if cache is None or cache[0] != key or cache[1] is not paint:
            cache = (key, paint, self.reference(paint))
            self._ref_cache = cache
        ref = cache[2]
        return ref if rows is None else ref[rows]

    def delta_e_rows(
        self,
        paint_a: FaceFlopTravelGloss,
        paint_b: FaceFlopTravelGloss,
        beta_deg: NDArray[np.float64],
        rows: NDArray[np.intp],
    ) -> NDArray[np.float64]:
        """Seam ΔE (C, B) for candidate rows (C,) each with its own β values (C, B), degrees."""
        normals = rotated_normals(beta_deg, self.hinge)  # (C, B, 3)
        ca = self._reference_cached(paint_a, rows)  # (C, 1, 3)
        if self.env is None:
            cb = point_colour(
                paint_b, self.L[rows], self.V[rows], normals, exposure=self.exposure, gloss=self.gloss
            )
        else:
            cb = np.stack(
                [
                    environment_colour(paint_b, self.env, self.V[r, 0], normals[i], gloss=self.gloss)
                    for i, r in enumerate(rows)
                ]
            )
        cb = self._unrotated_is_reference(paint_a, paint_b, ca, np.asarray(beta_deg, dtype=float), cb, rows)
        return self.difference(ca, cb, rows)

    def visible(self, beta_deg: NDArray[np.float64]) -> NDArray[np.bool_]:
        """(G, B): whether panel B, rotated by β, still faces the viewer (V·N_B > 0.01)."""
        normals = rotated_normals(np.asarray(beta_deg, dtype=float).reshape(-1), self.hinge)
        return np.sum(self.V * normals[None, :, :], axis=-1) > 0.01
