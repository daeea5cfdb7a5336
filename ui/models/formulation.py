"""The chemist's work on a design, as ``station snap`` / ``station formulate [--closed-loop]`` /
``station export`` do it (Qt-free; the screen runs these calls in a worker thread).

ColorSnap searches the library restricted to the chosen paint types (solid, metallic, pearl: the
library paint's ``type``); the recipe is formulated from the best matches' recipes
(``station.formulate.formulate_from_library``) and shown per colorant as mass fraction and as mass for
a batch; the closed loop sprays, measures (the SYNTHETIC spray-out panel model) and corrects until the
panel is within tolerance. The demo library and colorants are SYNTHETIC and every result says so.

In service mode (``station viewer --service URL``) the same four steps run on the service, against the
SERVICE's library (every stored library, or one of them): ``POST /api/v1/formulation/snap`` (with
``types`` and ``library``), ``/formulation/formulate``, ``/formulation/closed-loop`` (on the design
stored first with ``POST /designs``) and ``/formulation/export``. :class:`ServiceFormulation` does those
calls and returns what the screen shows in the same shape as the local calls (:class:`SnapView`, a
recipe result, a job with steps).
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from station.errors import InputError
from station.formulate.batch import DEFAULT_BATCH_G
from station.formulate.library import PAINT_TYPES, Library
from station.model import FaceFlopTravelGloss
from station.model.design_io import design_to_dict
from station.model.domain import ANGLES_3, METAMERISM_TEST_ILLUMINANTS

if TYPE_CHECKING:
    from ui.models.service import ServiceClient

BATCH_G_DEFAULT = DEFAULT_BATCH_G
"""Default batch size, grams (the CLI's and the service's)."""
BATCH_G_RANGE = (1.0, 1_000_000.0)
"""Batch sizes the screen's spin box offers, grams (the core accepts 0 < batch ≤ 1e6 g)."""
SPRAY_SEED = 7
"""Seed of the simulated spray-out panel (as ``station formulate --closed-loop``)."""


def checked_types(types: Iterable[str]) -> list[str]:
    """*types* sorted; :class:`InputError` naming ``types`` when none is chosen or one is not a paint type."""
    chosen = sorted(set(types))
    bad = [t for t in chosen if t not in PAINT_TYPES]
    if not chosen or bad:
        raise InputError("types", f"one or more of {', '.join(PAINT_TYPES)}", chosen)
    return chosen


def filtered(library: Library, types: Iterable[str]) -> Library:
    """The paints of *library* whose type is one of *types*; :class:`InputError` naming ``types``
    when none is chosen or one is not a paint type."""
    chosen = checked_types(types)
    if set(chosen) == set(PAINT_TYPES):
        return library
    sub = library.subset(np.isin(library.types, chosen), name=f"{library.name} ({'+'.join(chosen)})")
    if len(sub) == 0:
        raise InputError(
            "types", f"types the library holds ({', '.join(sorted(set(library.types)))})", chosen
        )
    return sub


def batch_rows(recipe: dict[str, float], batch_g: float) -> list[tuple[str, float, float]]:
    """(component, mass fraction, grams in a *batch_g* batch): the colorants, largest first, then the
    binder (``station.formulate.batch.batch_masses``: m_i = c_i·M, the binder the rest)."""
    from station.formulate.batch import batch_masses

    b = batch_masses(recipe, batch_g)  # FormulateInputError naming batch_g outside 0 < batch ≤ 1e6 g
    rows = [(name, recipe[name], b.colorants_g[name]) for name in sorted(recipe, key=lambda k: -recipe[k])]
    return [*rows, ("binder", b.binder_g / b.total_g, b.binder_g)]


@dataclass(frozen=True)
class SnapView:
    """What the screen shows of a ColorSnap: where it searched (*searched*, e.g. ``"demo (metallic), 3000
    paints"``), the matches best first as (code, paint type, ΣΔE00 over 15/45/110°, library) and the
    Fig. 5.10 warnings."""

    searched: str
    rows: tuple[tuple[str, str, float, str], ...]
    warnings: tuple[str, ...] = ()


def snap_view(library: Library, result: Any) -> SnapView:
    """:class:`SnapView` of a local ColorSnap *result* (``station.formulate.snap.SnapResult``) in *library*."""
    rows = tuple((m.code, str(library.types[m.index]), float(m.sum_de), library.name) for m in result.matches)
    return SnapView(f"{library.name}, {len(library)} paints", rows, tuple(result.warnings))


@dataclass(frozen=True)
class Formulation:
    """A formulation of one design against a filtered library: the ColorSnap matches the recipe started
    from (*snap*, ``formulate_from_library``'s k best), the recipe (*result*), the ColorSnap list the
    screen shows (*matches*: the same k = 5 as the ColorSnap button, so the list keeps its length) and
    the recipe's metamerism index per test illuminant (*metamerism*, worst over the angles; None where
    no reflectance reproduces the design)."""

    design: FaceFlopTravelGloss
    library: Library
    snap: Any  # station.formulate.SnapResult
    result: Any  # station.formulate.FormulationResult
    matches: SnapView | None = None
    metamerism: dict[str, float] | None = None

    @property
    def shown(self) -> SnapView:
        """The ColorSnap matches the screen lists (the k = 5 search; the starts are its first ones)."""
        return self.matches if self.matches is not None else snap_view(self.library, self.snap)


@dataclass(frozen=True)
class ServiceRecipe:
    """The service's recipe (``FormulationResult.to_dict()`` of ``POST /formulation/formulate``): the
    fields the screen shows, under the core result's names."""

    recipe: dict[str, float]
    start: str
    mean_de: float
    max_de: float
    formulable: bool
    tolerance: float
    message: str
    synthetic: bool
    recipes: tuple[dict[str, Any], ...] = ()


@dataclass(frozen=True)
class ServiceStep:
    """One spray-and-measure step of a service closed loop: its recipe (mass fractions) and, for a
    correction, the tinting additions (``Tinting.to_dict()``) to a batch of *batch_g* grams."""

    number: int
    kind: str
    mean_de: float
    recipe: dict[str, float] = field(default_factory=dict)
    additions: dict[str, Any] | None = None
    batch_g: float = BATCH_G_DEFAULT


@dataclass(frozen=True)
class ServiceJob:
    """A closed loop run on the service, stored there as formulation job *recipe_id* (``GET /recipes/{id}``)."""

    recipe_id: int
    design_id: int
    status: str
    message: str
    corrections: int
    steps: tuple[ServiceStep, ...]
    tolerance: float | None = None
    warnings: tuple[str, ...] = ()


@dataclass(frozen=True)
class ServiceFormulated:
    """A recipe formulated on the service for *design* from its matches (*shown*)."""

    design: FaceFlopTravelGloss
    shown: SnapView
    result: ServiceRecipe


class ServiceFormulation:
    """ColorSnap, formulation, closed loop and export through the service's routes, on its library.

    *library*: one stored library's name (``GET /library/libraries``), or None for every stored paint.
    Each call is one blocking HTTP request (run it in a worker); a refusal raises ``ServiceError`` with
    the service's message."""

    def __init__(self, client: ServiceClient, library: str | None = None) -> None:
        self.client = client
        self.library = library

    def libraries(self) -> list[dict[str, Any]]:
        """The service's stored libraries: name, paints, paints per type, synthetic flag."""
        return list(self.client.call("GET", "/library/libraries"))

    def snap(self, design: FaceFlopTravelGloss, types: Iterable[str], k: int = 5) -> SnapView:
        """``POST /formulation/snap``: CIEDE2000 ColorSnap of *design* at 15/45/110° in the service's
        library (``self.library``) restricted to *types*."""
        chosen = checked_types(types)
        body: dict[str, Any] = {"design": design_to_dict(design), "k": k, "metric": "cie2000"}
        if set(chosen) != set(PAINT_TYPES):
            body["types"] = chosen
        if self.library is not None:
            body["library"] = self.library
        got = self.client.call("POST", "/formulation/snap", json=body)
        rows = tuple(
            (str(m["code"]), str(m["type"]), float(m["sum_de"]), str(m["library"])) for m in got["matches"]
        )
        where = ", ".join(got["libraries"]) or "no library"
        searched = (
            f"service {self.client.url}: {where} ({'+'.join(got['types'])}), {got['library_paints']} paints"
        )
        return SnapView(searched, rows, tuple(got["warnings"]))

    def formulate(self, design: FaceFlopTravelGloss, types: Iterable[str] | None = None) -> ServiceFormulated:
        """``POST /formulation/formulate``: a recipe from the service library's recipe-bearing matches of
        *types* (all when ``None``) in the picked library (``self.library``; every library when ``None``)."""
        body: dict[str, Any] = {"design": design_to_dict(design)}
        if types is not None:
            body["types"] = checked_types(types)
        if self.library is not None:
            body["library"] = self.library
        got = self.client.call("POST", "/formulation/formulate", json=body)
        rows = tuple(
            (
                str(m["code"]),
                str(m.get("type", "")),
                float(m["sum_de"]),
                str(m.get("library", got.get("library", ""))),
            )
            for m in got["matches"]
        )
        shown = SnapView(
            f"service {self.client.url}: {got.get('library', '')}", rows, tuple(got["snap_warnings"])
        )
        result = ServiceRecipe(
            {str(k): float(v) for k, v in got["recipe"].items()},
            str(got.get("start", "")),
            float(got["mean_de"]),
            float(got["max_de"]),
            bool(got["formulable"]),
            float(got["tolerance"]),
            str(got["message"]),
            bool(got["synthetic_colorants"]),
            tuple(got.get("recipes") or ()),
        )
        return ServiceFormulated(design, shown, result)

    def closed_loop(self, design: FaceFlopTravelGloss, seed: int = SPRAY_SEED) -> ServiceJob:
        """Store *design* on the service (``POST /designs``), then ``POST /formulation/closed-loop`` on it
        (the service's spray-out simulation, seed *seed*); the job is stored there."""
        design_id = self.client.save_design(design.name or "formulated design", design, "closed loop")
        got = self.client.call(
            "POST", "/formulation/closed-loop", json={"design_id": design_id, "seed": seed}
        )
        steps = tuple(
            ServiceStep(
                int(st["number"]),
                str(st["kind"]),
                float(st["mean_de"]),
                {str(k): float(v) for k, v in (st.get("recipe") or {}).items()},
                st.get("additions"),
                float(st.get("batch_g", BATCH_G_DEFAULT)),
            )
            for st in got["steps"]
        )
        return ServiceJob(
            int(got["recipe_id"]),
            design_id,
            str(got["status"]),
            str(got["message"]),
            int(got["corrections"]),
            steps,
            None if got.get("tolerance") is None else float(got["tolerance"]),
            tuple(str(w) for w in got.get("warnings") or ()),
        )

    def export(self, design: FaceFlopTravelGloss, path: Path) -> tuple[Path, str | None]:
        """``POST /formulation/export`` (XML for ``.xml``, CxF3 for ``.cxf``) written to *path*; returns
        the path and the match code (header ``X-Match-Code``)."""
        path = Path(path)
        suffix = path.suffix.lower()
        if suffix not in (".xml", ".cxf"):
            raise InputError("file", "a name ending in .xml (thesis XML) or .cxf (CxF3)", path.name)
        body = {"design": design_to_dict(design), "format": suffix[1:], "match": True}
        r = self.client.checked("POST", "/formulation/export", json=body)
        path.write_bytes(r.content)
        return path, r.headers.get("X-Match-Code")


def snap(design: FaceFlopTravelGloss, library: Library, k: int = 5) -> Any:
    """ColorSnap (CIEDE2000, as the formulation uses) of *design* at 15/45/110° in *library*."""
    from station.formulate.snap import color_snap

    return color_snap(library, design.lab_at(np.array(ANGLES_3)), k=k, method="cie2000")


def formulate(design: FaceFlopTravelGloss, library: Library) -> Formulation:
    """The recipe from the ColorSnap matches' recipes (``formulate_from_library``, its default k = 3
    starts, as ``station formulate``), the k = 5 ColorSnap list the screen shows, and the recipe's
    metamerism index (:func:`recipe_metamerism`). A miss carries the colorant-limited gamut's sentence
    in its message (``station.formulate.gamut.formulate_in_gamut``)."""
    from station.formulate.gamut import formulate_in_gamut

    result, found = formulate_in_gamut(
        design.lab_at(np.array(ANGLES_3)), library, gloss_gu=design.gloss_target_gu
    )
    shown = snap_view(library, snap(design, library))
    ranked = bool(getattr(result, "recipes", ()))  # ranked recipes carry their own metamerism index
    return Formulation(design, library, found, result, shown, None if ranked else recipe_metamerism(result))


def recipe_metamerism(result: Any) -> dict[str, float] | None:
    """Metamerism index (CIEDE2000, reference D65) of *result*'s recipe under each test illuminant
    (:data:`station.model.domain.METAMERISM_TEST_ILLUMINANTS`, A and F11), the worst over the angles
    (``station.formulate.metamerism.rank_formulation`` on the recipe alone); None when no reflectance
    reproduces the design (e.g. a specular L* over 100)."""
    from station.formulate.errors import FormulateInputError
    from station.formulate.metamerism import rank_formulation

    try:
        ranking = rank_formulation(result, METAMERISM_TEST_ILLUMINANTS)
    except FormulateInputError:
        return None
    return {str(name): float(max(v)) for name, v in ranking.best.index.items()}


def closed_loop(f: Formulation, seed: int = SPRAY_SEED, batch_g: float = BATCH_G_DEFAULT) -> Any:
    """Spray, measure and correct by tinting a batch of *batch_g* g (``station.formulate.closed_loop`` on
    the SYNTHETIC spray-out model; a :class:`FormulateInputError` names ``batch_g`` outside the range
    the scale allows)."""
    from station.formulate.closed_loop import closed_loop as run
    from station.formulate.formulation import FormulationOptions, formulation_options
    from station.formulate.sprayout import SprayOutModel

    options = formulation_options(FormulationOptions(batch_g=batch_g))

    spray = SprayOutModel(seed=seed)
    recipes = f.library.recipes
    if recipes is None:
        raise InputError("library", "a library with recipes (e.g. the demo library)", f.library.name)
    starts = [(m.code, recipes[m.index]) for m in f.snap.matches]
    return run(
        f.design.lab_at(np.array(ANGLES_3)),
        spray.measure,
        starts=starts,
        gloss_gu=f.design.gloss_target_gu,
        tolerance=f.result.tolerance,
        options=options,
    )


def export(
    design: FaceFlopTravelGloss,
    library: Library,
    path: Path,
    result: Any = None,
    batch_g: float = BATCH_G_DEFAULT,
) -> tuple[Path, str | None]:
    """Write the design, its ColorSnap match and — with a library carrying recipes — its recipe as a
    prediction colour, as ``station export --recipe`` does: thesis XML (``.xml``) or CxF3 (``.cxf``, with
    the recipe in grams for a *batch_g* g batch and the predicted spectra per geometry,
    ``station.formulate.export.recipe_export``). *result*: the recipe already formulated for *design*
    (formulated here when None). Returns the path and the match code."""
    from station.formulate.color_xml import write_color_xml
    from station.formulate.cxf import specs_to_cxf
    from station.formulate.export import export_specs, recipe_export

    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in (".xml", ".cxf"):
        raise InputError("file", "a name ending in .xml (thesis XML) or .cxf (CxF3)", path.name)
    specs, code = export_specs(design, library, method="cie76")
    extras: list[Any] = [None] * len(specs)
    if library.recipes is not None:
        if result is None:
            from station.formulate.formulation import formulate_from_library

            lab = design.lab_at(np.array(ANGLES_3))
            result, _found = formulate_from_library(lab, library, gloss_gu=design.gloss_target_gu)
        spec, extra = recipe_export(result, name=f"{design.name or 'design'} recipe", batch_g=batch_g)
        specs.append(spec)
        extras.append(extra)
    if suffix == ".xml":
        write_color_xml(specs, path)
    else:
        path.write_bytes(specs_to_cxf(specs, extras))
    return path, code
