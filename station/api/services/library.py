"""The paint library: browse, and load station.formulate's demo library on first start."""

from __future__ import annotations

import importlib
import logging
from typing import Any

from sqlalchemy import func, insert, select
from sqlalchemy.orm import Session

from db.models import LibraryPaint
from station.api.errors import NotFoundError

log = logging.getLogger(__name__)
_CHUNK = 1000


def list_paints(
    *, session: Session, category: str | None, code_prefix: str | None, limit: int, offset: int
) -> tuple[list[LibraryPaint], int]:
    """Library paints by category (``solid``/``metallic``/``pearl``) and code prefix."""
    query = select(LibraryPaint)
    if category:
        query = query.where(LibraryPaint.category == category)
    if code_prefix:
        query = query.where(LibraryPaint.code.startswith(code_prefix, autoescape=True))
    total = session.scalar(select(func.count()).select_from(query.subquery())) or 0
    rows = session.scalars(query.order_by(LibraryPaint.code).limit(limit).offset(offset)).all()
    return list(rows), total


def get_paint(*, session: Session, code: str) -> LibraryPaint:
    """The paint with *code* or :class:`NotFoundError`."""
    paint = session.scalar(select(LibraryPaint).where(LibraryPaint.code == code))
    if paint is None:
        raise NotFoundError(f"library paint {code!r} not found")
    return paint


def library_rows(lib: Any) -> list[dict[str, Any]]:
    """Rows of ``library_paints`` for a ``station.formulate.library.Library``."""
    top, kind, group = lib.groups()
    names = tuple(lib.colorant_names or ())
    rows = []
    for i in range(len(lib)):
        recipe = None
        if lib.recipes is not None:
            recipe = {n: float(x) for n, x in zip(names, lib.recipes[i], strict=True) if x > 0}
        rows.append(
            {
                "code": str(lib.codes[i]),
                "name": str(lib.codes[i]),
                "category": str(lib.types[i]),
                "family": f"{top[i]}/{kind[i]}/{group[i]}",
                "angles_deg": [float(a) for a in lib.angles_deg],
                "lab": lib.lab[i].round(4).tolist(),
                "gloss_gu": float(lib.gloss_gu[i]),
                "extra": {"recipe": recipe, "synthetic": bool(lib.synthetic), "library": lib.name},
            }
        )
    return rows


def load_demo_library(*, session: Session) -> int:
    """Load ``station.formulate.demo.demo_library()`` when the table is empty; returns rows added.

    The formulation package is imported lazily; when it is missing the load is skipped with a log line.
    """
    if (session.scalar(select(func.count()).select_from(LibraryPaint)) or 0) > 0:
        return 0
    try:
        demo = importlib.import_module("station.formulate.demo")
    except ImportError as exc:
        log.warning("demo library not loaded: station.formulate.demo unavailable (%s)", exc)
        return 0
    rows = library_rows(demo.demo_library())
    for start in range(0, len(rows), _CHUNK):
        session.execute(insert(LibraryPaint), rows[start : start + _CHUNK])
    session.commit()
    log.info("demo library loaded: %d synthetic paints", len(rows))
    return len(rows)
