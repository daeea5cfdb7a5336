"""The demo library's rows fit the schema on both backends (PostgreSQL enforces string lengths)."""

from __future__ import annotations

from sqlalchemy import func, insert, select

from db.engine import make_engine, make_sessionmaker
from db.models import LibraryPaint
from station.api.services.library import library_rows
from station.formulate.demo import generate_library


def test_library_rows_load(database_url: str) -> None:
    lib = generate_library(n_solid=30, n_metallic=30, n_pearl=30, seed=5)
    rows = library_rows(lib)
    assert max(len(r["family"]) for r in rows) > 32  # the full hierarchy path, e.g. metallics+pearls/…
    engine = make_engine(database_url)
    try:
        with make_sessionmaker(engine)() as session:
            session.execute(insert(LibraryPaint), rows)
            session.commit()
            assert session.scalar(select(func.count()).select_from(LibraryPaint)) == 90
            stored = session.scalar(select(LibraryPaint).where(LibraryPaint.code == rows[0]["code"]))
            assert stored is not None
            assert stored.lab == rows[0]["lab"] and stored.family == rows[0]["family"]
    finally:
        engine.dispose()
