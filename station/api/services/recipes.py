"""Formulation jobs: ColorSnap a design version against the library in the database (thesis §5.3.5).

The snap index (``station.formulate.snap.SnapIndex``, exact top-k) is built from the ``library_paints``
rows once and cached on the app until the row count changes.
"""

from __future__ import annotations

import threading
from dataclasses import dataclass
from typing import Any

import numpy as np
from sqlalchemy import func, select
from sqlalchemy.orm import Session

from db.models import Design, DesignVersion, FormulationJob, LibraryPaint, User
from station.api.errors import ConflictError, NotFoundError
from station.api.schemas.recipes import RecipeCreate, RecipePublic
from station.api.services import audit
from station.model.design_io import design_from_dict

ANGLES = (15.0, 45.0, 110.0)


@dataclass
class _Snap:
    count: int
    index: Any
    ids: np.ndarray
    codes: list[str]
    recipes: list[dict[str, float] | None]


class SnapCache:
    """The snap index over the database library, rebuilt when the number of paints changes."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._snap: _Snap | None = None

    def get(self, session: Session) -> _Snap:
        from station.formulate.snap import SnapIndex

        count = session.scalar(select(func.count()).select_from(LibraryPaint)) or 0
        with self._lock:
            if self._snap is not None and self._snap.count == count:
                return self._snap
            if count == 0:
                raise ConflictError("the paint library is empty: load one (station serve loads the demo library)")
            rows = session.execute(select(LibraryPaint.id, LibraryPaint.code, LibraryPaint.angles_deg,
                                          LibraryPaint.lab, LibraryPaint.extra).order_by(LibraryPaint.id)).all()
            lab = np.empty((len(rows), len(ANGLES), 3))
            for i, row in enumerate(rows):
                angles = [float(a) for a in row.angles_deg]
                lab[i] = [row.lab[angles.index(a)] for a in ANGLES]
            self._snap = _Snap(count, SnapIndex(lab, ANGLES), np.array([r.id for r in rows]),
                               [r.code for r in rows], [(r.extra or {}).get("recipe") for r in rows])
            return self._snap


def _design_version(session: Session, design_id: int, version: int | None) -> DesignVersion:
    design = session.get(Design, design_id)
    if design is None:
        raise NotFoundError(f"design {design_id} not found")
    wanted = version or design.latest_version
    row = session.scalar(select(DesignVersion).where(DesignVersion.design_id == design_id,
                                                     DesignVersion.version == wanted))
    if row is None:
        raise NotFoundError(f"design {design_id} has no version {wanted}")
    return row


def create_recipe(*, session: Session, actor: User, cache: SnapCache, recipe_in: RecipeCreate) -> RecipePublic:
    """Snap the design version to the library, store the job with its candidates, return it."""
    dv = _design_version(session, recipe_in.design_id, recipe_in.version)
    target = np.asarray(design_from_dict(dv.body).lab_at(np.asarray(ANGLES)), dtype=float)
    snap = cache.get(session)
    rows, sums, per_angle = snap.index.query(target, k=recipe_in.k, method=recipe_in.metric)
    candidates = [{"code": snap.codes[r], "library_paint_id": int(snap.ids[r]), "sum_de": float(s),
                   "de_per_angle": [float(x) for x in pa], "recipe": snap.recipes[r]}
                  for r, s, pa in zip(rows, sums, per_angle, strict=True)]
    job = FormulationJob(
        design_version_id=dv.id, library_paint_id=candidates[0]["library_paint_id"], state="done",
        target={"metric": recipe_in.metric, "angles_deg": list(ANGLES), "lab": target.round(4).tolist()},
        recipe={"candidates": candidates, "recipe": candidates[0]["recipe"], "warnings": []},
        created_by_id=actor.id,
    )
    session.add(job)
    session.flush()
    audit.record(session=session, actor=actor, action="recipe.create", entity="recipe", entity_id=job.id,
                 design_id=recipe_in.design_id, version=dv.version, best=candidates[0]["code"])
    session.commit()
    return RecipePublic.from_job(job, dv.design_id, dv.version)


def get_recipe(*, session: Session, recipe_id: int) -> RecipePublic:
    """Formulation job *recipe_id*."""
    row = session.execute(select(FormulationJob, DesignVersion.design_id, DesignVersion.version)
                          .join(DesignVersion, DesignVersion.id == FormulationJob.design_version_id)
                          .where(FormulationJob.id == recipe_id)).first()
    if row is None:
        raise NotFoundError(f"recipe {recipe_id} not found")
    return RecipePublic.from_job(*row)


def list_recipes(*, session: Session, design_id: int | None, limit: int, offset: int) -> tuple[list[RecipePublic], int]:
    """Formulation jobs, newest first."""
    query = (select(FormulationJob, DesignVersion.design_id, DesignVersion.version)
             .join(DesignVersion, DesignVersion.id == FormulationJob.design_version_id))
    if design_id is not None:
        query = query.where(DesignVersion.design_id == design_id)
    total = session.scalar(select(func.count()).select_from(query.subquery())) or 0
    rows = session.execute(query.order_by(FormulationJob.id.desc()).limit(limit).offset(offset)).all()
    return [RecipePublic.from_job(*r) for r in rows], total
