"""Formulation over the library in the database: ColorSnap, recipes, export, CSV import and export.

The library rows are turned into one ``station.formulate.library.Library`` and its exact ColorSnap index
(``SnapIndex``) once per library per app: :class:`LibraryCache` lives on ``app.state`` and rebuilds only
when the rows change (count or newest id). A search restricted to one named stored library uses that
library's own index, built on its first use and kept until the rows change (:meth:`LibraryCache.named`). Paints with a recipe in the colorant database's names form a
second library (with its own index) that formulation starts from. The demo library and the colorants
are SYNTHETIC; every result says so.
"""

from __future__ import annotations

import io
import threading
from dataclasses import dataclass
from typing import Any

import numpy as np
from sqlalchemy import func, insert, select
from sqlalchemy.orm import Session

from db.models import LibraryPaint, User
from station.api.errors import ConflictError
from station.api.schemas.formulation import DesignSource, ExportRequest, FormulateRequest, SnapRequest
from station.api.services import audit
from station.api.services.designs import design_version, to_design
from station.api.services.library import library_rows
from station.errors import InputError
from station.model import FaceFlopTravelGloss
from station.model.design_io import design_from_dict
from station.model.domain import ANGLES_3, PAINT_TYPES

STANDARD = ANGLES_3


@dataclass(frozen=True)
class CachedLibrary:
    """The database library as a core ``Library`` with its snap index, and the recipe-bearing subset."""

    key: tuple[int, int]
    library: Any
    index: Any
    ids: np.ndarray
    recipes: list[dict[str, float] | None]
    with_recipes: Any | None
    with_recipes_index: Any | None
    with_recipes_rows: np.ndarray
    library_names: np.ndarray
    synthetic_rows: np.ndarray


@dataclass(frozen=True)
class NamedLibrary:
    """One named stored library: its rows in the cached library, the subset ``Library`` and its index
    (``library`` and ``index`` are ``None`` when no row carries the name)."""

    rows: np.ndarray
    library: Any | None
    index: Any | None


class LibraryCache:
    """One :class:`CachedLibrary` per app, rebuilt when the ``library_paints`` rows change, and the named
    libraries' indices (:meth:`named`), dropped with it. ``builds`` and ``named_builds`` count the builds."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._cached: CachedLibrary | None = None
        self._named: dict[tuple[str, bool], NamedLibrary] = {}
        self.builds = 0
        self.named_builds = 0

    def named(self, cached: CachedLibrary, name: str, with_recipes: bool) -> NamedLibrary:
        """The stored library *name* of *cached* (its recipe-bearing paints when *with_recipes*), with its
        exact ColorSnap index: built once per name while the rows stay the same."""
        with self._lock:
            if cached is not self._cached:  # rows changed meanwhile: answer this request, keep nothing
                return _named(cached, name, with_recipes)
            key = (name, with_recipes)
            hit = self._named.get(key)
            if hit is None:
                hit = self._named[key] = _named(cached, name, with_recipes)
                self.named_builds += 1
            return hit

    def get(self, session: Session) -> CachedLibrary:
        """The cached library, (re)built from the rows when needed; 409 when the table is empty."""
        count, newest = session.execute(select(func.count(LibraryPaint.id), func.max(LibraryPaint.id))).one()
        key = (int(count or 0), int(newest or 0))
        with self._lock:
            if self._cached is not None and self._cached.key == key:
                return self._cached
            if key[0] == 0:
                raise ConflictError(
                    "the paint library is empty: load one (station serve loads the demo library)"
                )
            self._cached = _build(session, key)
            self._named = {}
            self.builds += 1
            return self._cached


def _named(cached: CachedLibrary, name: str, with_recipes: bool) -> NamedLibrary:
    """:meth:`LibraryCache.named` without the cache."""
    from station.formulate.snap import SnapIndex

    if with_recipes:
        base, base_rows = cached.with_recipes, cached.with_recipes_rows
    else:
        base, base_rows = cached.library, np.arange(len(cached.library))
    keep = np.flatnonzero(cached.library_names[base_rows] == name)
    if base is None or keep.size == 0:
        return NamedLibrary(base_rows[keep], None, None)
    sub = base.subset(keep)
    return NamedLibrary(base_rows[keep], sub, SnapIndex(sub))


def _build(session: Session, key: tuple[int, int]) -> CachedLibrary:
    from station.formulate.colorants import default_database
    from station.formulate.library import Library
    from station.formulate.snap import SnapIndex

    rows = session.execute(select(LibraryPaint).order_by(LibraryPaint.id)).scalars().all()
    common = set.intersection(*({float(a) for a in r.angles_deg} for r in rows))
    if not set(STANDARD) <= common:
        raise ConflictError("the library's paints do not share Lab at 15°, 45° and 110°")
    angles = tuple(sorted(common))
    lab = np.empty((len(rows), len(angles), 3))
    for i, r in enumerate(rows):
        where = {float(a): j for j, a in enumerate(r.angles_deg)}
        lab[i] = [r.lab[where[a]] for a in angles]
    extras = [r.extra or {} for r in rows]
    recipes = [x.get("recipe") for x in extras]
    given = {i: rc for i, rc in enumerate(recipes) if isinstance(rc, dict)}
    names = sorted({str(x.get("library", "database")) for x in extras})
    lib = Library(
        name=" + ".join(names),
        codes=np.array([r.code for r in rows]),
        types=np.array([r.category for r in rows]),
        gloss_gu=np.array([np.nan if r.gloss_gu is None else r.gloss_gu for r in rows], dtype=float),
        angles_deg=angles,
        lab=lab,
        synthetic=all(bool(x.get("synthetic")) for x in extras),
        source="database",
    )
    colorants = default_database().names
    has = np.array([isinstance(rc, dict) and set(rc) <= set(colorants) for rc in recipes], dtype=bool)
    with_recipes = with_index = None
    rows_with = np.flatnonzero(has)
    if rows_with.size:
        conc = np.array([[float(given[int(i)].get(n, 0.0)) for n in colorants] for i in rows_with])
        with_recipes = Library(
            name=lib.name,
            codes=lib.codes[rows_with],
            types=lib.types[rows_with],
            gloss_gu=lib.gloss_gu[rows_with],
            angles_deg=angles,
            lab=lab[rows_with],
            synthetic=lib.synthetic,
            recipes=conc,
            colorant_names=colorants,
            source="database",
        )
        with_index = SnapIndex(with_recipes)
    return CachedLibrary(
        key,
        lib,
        SnapIndex(lib),
        np.array([r.id for r in rows]),
        recipes,
        with_recipes,
        with_index,
        rows_with,
        np.array([str(x.get("library", "database")) for x in extras]),
        np.array([bool(x.get("synthetic")) for x in extras], dtype=bool),
    )


def _target(session: Session, source: DesignSource) -> tuple[np.ndarray, FaceFlopTravelGloss | None]:
    """Lab at 15/45/110 (and the design, when there is one) of the request's source."""
    if source.lab is not None:
        return np.asarray(source.lab, dtype=float), None
    if source.design is not None:
        design = to_design(source.design)
    else:
        design = design_from_dict(
            design_version(session=session, design_id=source.design_id or 0, version=source.version).body
        )
    return np.asarray(design.lab_at(np.asarray(STANDARD)), dtype=float), design


def snap(*, session: Session, cache: LibraryCache, request: SnapRequest) -> dict[str, Any]:
    """ColorSnap top-k against the database library (``station.formulate.snap.color_snap``), optionally
    one stored library only (``request.library``) and some paint types only (``request.types``); every
    match says its library and whether it is synthetic."""
    from station.formulate.snap import color_snap, type_rows

    lab, _ = _target(session, request)
    cached = cache.get(session)
    lib, index, rows = cached.library, cached.index, np.arange(len(cached.library))
    if request.library is not None:
        named = cache.named(cached, request.library, with_recipes=False)
        if named.library is None:
            held = " | ".join(sorted(set(cached.library_names.tolist())))
            raise InputError("library", f"a stored library: {held}", request.library)
        lib, index, rows = named.library, named.index, named.rows
    type_rows(lib, request.types, field="types")  # 422 naming ``types`` before the search
    result = color_snap(
        lib, lab, k=min(request.k, len(lib)), method=request.metric, index=index, types=request.types
    )
    out = result.to_dict()
    hits = [int(rows[m.index]) for m in result.matches]
    out["matches"] = [
        {
            "code": m.code,
            "library_paint_id": int(cached.ids[r]),
            "type": str(cached.library.types[r]),
            "library": str(cached.library_names[r]),
            "synthetic": bool(cached.synthetic_rows[r]),
            "sum_de": m.sum_de,
            "de_per_angle": list(m.de_per_angle),
            "recipe": cached.recipes[r],
        }
        for m, r in zip(result.matches, hits, strict=True)
    ]
    searched = rows if request.types is None else rows[np.isin(cached.library.types[rows], request.types)]
    out.update(
        design_lab=np.asarray(result.design_lab, dtype=float).tolist(),
        library_paints=int(searched.size),
        libraries=sorted(set(cached.library_names[searched].tolist())),
        types=sorted(request.types or PAINT_TYPES),
        synthetic=any(bool(cached.synthetic_rows[r]) for r in hits),
    )
    return out


def stored_libraries(*, session: Session, cache: LibraryCache) -> list[dict[str, object]]:
    """Each stored library (``extra.library`` of its paints): paints per type and its synthetic flag."""
    cached = cache.get(session)
    out: list[dict[str, object]] = []
    for name in sorted(set(cached.library_names.tolist())):
        rows = cached.library_names == name
        types = cached.library.types[rows]
        out.append(
            {
                "name": name,
                "paints": int(rows.sum()),
                "types": {t: int(np.sum(types == t)) for t in PAINT_TYPES},
                "synthetic": bool(cached.synthetic_rows[rows].all()),
            }
        )
    return out


def formulate(*, session: Session, cache: LibraryCache, request: FormulateRequest) -> dict[str, Any]:
    """Recipe for the target from the matches' recipes (``station.formulate.gamut.formulate_in_gamut``:
    a miss says whether the colorant limit or the toner line refuses the design); nothing is stored.
    With ``illuminants`` the candidate recipes ranked by metamerism index (``station.formulate.metamerism``)."""
    from station.formulate.gamut import formulate_in_gamut
    from station.formulate.metamerism import chosen_illuminants, rank_formulation
    from station.formulate.options import FormulationOptions, formulation_options

    lab, design = _target(session, request)
    gloss = (
        request.gloss_gu
        if request.gloss_gu is not None
        else (design.gloss_target_gu if design is not None else None)
    )
    from station.formulate.snap import type_rows

    cached = cache.get(session)
    if cached.with_recipes is None:
        raise ConflictError("no library paint has a recipe in the colorant database: load the demo library")
    lib, index = cached.with_recipes, cached.with_recipes_index
    rows = cached.with_recipes_rows
    if request.library is not None:
        named = cache.named(cached, request.library, with_recipes=True)
        if named.library is None:
            held = " | ".join(sorted(set(cached.library_names[rows].tolist())))
            raise InputError("library", f"a stored library with recipes: {held}", request.library)
        lib, index, rows = named.library, named.index, named.rows
    type_rows(lib, request.types, field="types")  # 422 naming ``types`` before formulating
    illuminants = () if request.illuminants is None else chosen_illuminants(request.illuminants)
    result, matches = formulate_in_gamut(
        lab,
        lib,
        index=index,
        k=min(request.k, len(lib)),
        gloss_gu=gloss,
        tolerance=request.tolerance,
        types=request.types,
        candidates=request.candidates if illuminants else 0,
        options=formulation_options(
            FormulationOptions(
                line=request.line,
                max_colorants=request.max_colorants,
                scale_resolution_g=request.scale_resolution_g,
            )
        ),
    )
    out = result.to_dict()
    if illuminants:
        out["metamerism_ranking"] = rank_formulation(result, illuminants).to_dict()
    out["matches"] = [
        {
            "code": m.code,
            "type": str(cached.library.types[rows[m.index]]),
            "library": str(cached.library_names[rows[m.index]]),
            "sum_de": m.sum_de,
            "de_per_angle": list(m.de_per_angle),
            "library_paint_id": int(cached.ids[rows[m.index]]),
        }
        for m in matches.matches
    ]
    out["snap_warnings"] = list(matches.warnings)
    out["library"] = cached.library.name if request.library is None else request.library
    return out


def export(*, session: Session, cache: LibraryCache, request: ExportRequest) -> tuple[bytes, str, str | None]:
    """The design (both 3-angle sets, optionally 5) and its ColorSnap match as XML or CxF3 bytes; returns
    (bytes, file name, match code)."""
    from station.formulate.color_xml import colors_to_xml
    from station.formulate.cxf import specs_to_cxf
    from station.formulate.export import export_specs

    if request.design is not None:
        design = to_design(request.design)
    else:
        design = design_from_dict(
            design_version(session=session, design_id=request.design_id or 0, version=request.version).body
        )
    if request.match:
        cached = cache.get(session)
        specs, code = export_specs(
            design, cached.library, method=request.metric, five_angles=request.five_angles, index=cached.index
        )
    else:
        specs, code = export_specs(design, five_angles=request.five_angles)
    data = colors_to_xml(specs) if request.format == "xml" else specs_to_cxf(specs)
    stem = (
        "".join(ch if ch.isalnum() or ch in "-_" else "_" for ch in (design.name or "design"))[:64]
        or "design"
    )
    return data, f"{stem}.{'xml' if request.format == 'xml' else 'cxf'}", code


def import_csv(
    *, session: Session, actor: User, text: str, name: str, allow_formulas: bool = False
) -> dict[str, Any]:
    """Validate a library CSV (``read_library_csv``) and add its paints; a code already stored is a 409 and
    nothing is added (one transaction). A code starting like a spreadsheet formula is refused unless
    *allow_formulas*."""
    from station.formulate.library_csv import read_library_csv

    lib = read_library_csv(io.StringIO(text), name=name, allow_formulas=allow_formulas)
    codes = [str(c) for c in lib.codes]
    taken = (
        session.scalars(select(LibraryPaint.code).where(LibraryPaint.code.in_(codes))).all() if codes else []
    )
    if taken:
        raise ConflictError(f"{len(taken)} code(s) already in the library, e.g. {sorted(taken)[0]!r}")
    rows = library_rows(lib)
    for start in range(0, len(rows), 1000):
        session.execute(insert(LibraryPaint), rows[start : start + 1000])
    audit.record(
        session=session,
        actor=actor,
        action="library.import",
        entity="library",
        entity_id=name,
        paints=len(rows),
    )
    session.commit()
    return {
        "library": lib.name,
        "paints": len(rows),
        "angles_deg": list(lib.angles_deg),
        "types": {t: int(np.sum(lib.types == t)) for t in PAINT_TYPES},
    }


def export_csv(*, session: Session, cache: LibraryCache, category: str | None) -> str:
    """The database library (optionally one category) as library CSV text (``write_library_csv``)."""
    from station.formulate.library_csv import write_library_csv

    lib = cache.get(session).library
    if category:
        lib = lib.subset(lib.types == category)
    buf = io.StringIO()
    write_library_csv(lib, buf)
    return buf.getvalue()


def app_cache(state: Any) -> LibraryCache:
    """The app's :class:`LibraryCache` (``app.state.library_cache``), created on first use."""
    cache = getattr(state, "library_cache", None)
    if cache is None:
        cache = state.library_cache = LibraryCache()
    return cache


def browse(*, session: Session, cache: LibraryCache, flt: Any, limit: int, offset: int) -> dict[str, Any]:
    """The thesis's browser (§5.3.3): ``LibraryFilter`` (types, index bounds, hierarchy) over the library."""
    from station.formulate.library import hierarchy_counts

    cached = cache.get(session)
    lib = cached.library
    rows = np.flatnonzero(flt.mask(lib))
    idx = lib.indices()  # computed once per cached library
    top, kind, group = lib.groups()
    std = lib.angle_columns()
    paints = [
        {
            "code": str(lib.codes[r]),
            "library_paint_id": int(cached.ids[r]),
            "type": str(lib.types[r]),
            "gloss_gu": None if np.isnan(lib.gloss_gu[r]) else float(lib.gloss_gu[r]),
            "group": [str(top[r]), str(kind[r]), str(group[r])],
            "lab_15_45_110": std[r].tolist(),
            "indices": {k: (None if np.isnan(v[r]) else float(v[r])) for k, v in idx.items()},
        }
        for r in rows[offset : offset + limit]
    ]
    return {
        "library": lib.name,
        "synthetic": bool(lib.synthetic),
        "matched": int(rows.size),
        "paints": paints,
        "hierarchy": hierarchy_counts(lib),
    }


def closed_loop(*, session: Session, actor: User, cache: LibraryCache, request: Any) -> dict[str, Any]:
    """Formulate → simulated spray-out → simulated measurement → correct (``station.formulate.closed_loop``),
    stored as one formulation job with its history and audited."""
    from db.models import FormulationJob
    from station.formulate.closed_loop import closed_loop as run_closed_loop
    from station.formulate.snap import color_snap
    from station.formulate.sprayout import SprayOutModel

    dv = design_version(session=session, design_id=request.design_id, version=request.version)
    design = design_from_dict(dv.body)
    lab = np.asarray(design.lab_at(np.asarray(STANDARD)), dtype=float)
    gloss = request.gloss_gu if request.gloss_gu is not None else design.gloss_target_gu
    cached = cache.get(session)
    if cached.with_recipes is None:
        raise ConflictError("no library paint has a recipe in the colorant database: load the demo library")
    lib = cached.with_recipes
    snapped = color_snap(lib, lab, k=min(3, len(lib)), method="cie2000", index=cached.with_recipes_index)
    starts = [(m.code, lib.recipes[m.index]) for m in snapped.matches]
    job = run_closed_loop(
        lab,
        SprayOutModel(seed=request.seed).measure,
        starts=starts,
        gloss_gu=gloss,
        tolerance=request.tolerance,
        max_corrections=request.corrections,
    )
    out = job.to_dict()
    out["measurement"] = f"simulated spray-out panel model (SYNTHETIC), seed {request.seed}"
    best = snapped.matches[0]
    row = FormulationJob(
        design_version_id=dv.id,
        library_paint_id=int(cached.ids[cached.with_recipes_rows[best.index]]),
        state="done" if job.status == "converged" else "failed",
        target={
            "metric": "cie2000",
            "angles_deg": list(STANDARD),
            "lab": lab.round(4).tolist(),
            "gloss_gu": gloss,
        },
        recipe={
            "candidates": [],
            "recipe": job.final_recipe,
            "warnings": list(snapped.warnings),
            "closed_loop": out,
        },
        created_by_id=actor.id,
    )
    session.add(row)
    session.flush()
    audit.record(
        session=session,
        actor=actor,
        action="recipe.closed_loop",
        entity="recipe",
        entity_id=row.id,
        design_id=request.design_id,
        version=dv.version,
        status=job.status,
        corrections=job.corrections,
    )
    session.commit()
    return {"recipe_id": row.id, **out}
