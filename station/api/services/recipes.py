"""Formulation jobs: ColorSnap a design version against the library in the database (thesis §5.3.5).

The snap index (``station.formulate.snap.SnapIndex``, exact top-k) is the app's one
:class:`~station.api.services.formulation.LibraryCache` (built once per library, on ``app.state``).
"""

from __future__ import annotations

import numpy as np
from sqlalchemy import func, select
from sqlalchemy.orm import Session

from db.models import DesignVersion, FormulationJob, User
from station.api.errors import NotFoundError
from station.api.schemas.recipes import RecipeCreate, RecipePublic
from station.api.services import audit
from station.api.services.designs import design_version
from station.api.services.formulation import LibraryCache
from station.model.design_io import design_from_dict
from station.model.domain import ANGLES_3

ANGLES = ANGLES_3


def _design_version(session: Session, design_id: int, version: int | None) -> DesignVersion:
    return design_version(session=session, design_id=design_id, version=version)


def create_recipe(
    *, session: Session, actor: User, cache: LibraryCache, recipe_in: RecipeCreate
) -> RecipePublic:
    """Snap the design version to the library, store the job with its candidates, return it."""
    dv = _design_version(session, recipe_in.design_id, recipe_in.version)
    target = np.asarray(design_from_dict(dv.body).lab_at(np.asarray(ANGLES)), dtype=float)
    snap = cache.get(session)
    rows, sums, per_angle = snap.index.query(
        target, k=min(recipe_in.k, len(snap.library)), method=recipe_in.metric
    )
    candidates = [
        {
            "code": str(snap.library.codes[r]),
            "library_paint_id": int(snap.ids[r]),
            "sum_de": float(s),
            "de_per_angle": [float(x) for x in pa],
            "recipe": snap.recipes[r],
        }
        for r, s, pa in zip(rows, sums, per_angle, strict=True)
    ]
    job = FormulationJob(
        design_version_id=dv.id,
        library_paint_id=candidates[0]["library_paint_id"],
        state="done",
        target={"metric": recipe_in.metric, "angles_deg": list(ANGLES), "lab": target.round(4).tolist()},
        recipe={"candidates": candidates, "recipe": candidates[0]["recipe"], "warnings": []},
        created_by_id=actor.id,
    )
    session.add(job)
    session.flush()
    audit.record(
        session=session,
        actor=actor,
        action="recipe.create",
        entity="recipe",
        entity_id=job.id,
        design_id=recipe_in.design_id,
        version=dv.version,
        best=candidates[0]["code"],
    )
    session.commit()
    return RecipePublic.from_job(job, dv.design_id, dv.version)


def get_recipe(*, session: Session, recipe_id: int) -> RecipePublic:
    """Formulation job *recipe_id*."""
    row = session.execute(
        select(FormulationJob, DesignVersion.design_id, DesignVersion.version)
        .join(DesignVersion, DesignVersion.id == FormulationJob.design_version_id)
        .where(FormulationJob.id == recipe_id)
    ).first()
    if row is None:
        raise NotFoundError(f"recipe {recipe_id} not found")
    return RecipePublic.from_job(*row)


def list_recipes(
    *, session: Session, design_id: int | None, limit: int, offset: int
) -> tuple[list[RecipePublic], int]:
    """Formulation jobs, newest first."""
    query = select(FormulationJob, DesignVersion.design_id, DesignVersion.version).join(
        DesignVersion, DesignVersion.id == FormulationJob.design_version_id
    )
    if design_id is not None:
        query = query.where(DesignVersion.design_id == design_id)
    total = session.scalar(select(func.count()).select_from(query.subquery())) or 0
    rows = session.execute(query.order_by(FormulationJob.id.desc()).limit(limit).offset(offset)).all()
    return [RecipePublic.from_job(*r) for r in rows], total
