"""Apply, revert and inspect Alembic migrations programmatically (``station db …`` uses these).

The Alembic environment ships inside the package (``db/alembic.ini``, ``db/migrations``), so an
installed workstation can migrate without a source checkout.
"""

from __future__ import annotations

from pathlib import Path

from alembic import command
from alembic.config import Config
from alembic.runtime.migration import MigrationContext
from alembic.script import ScriptDirectory
from sqlalchemy import Engine

from db.engine import make_engine, normalise_url
from db.errors import MigrationError

HERE = Path(__file__).resolve().parent


def alembic_config(url: str) -> Config:
    """The Alembic configuration for *url* (passed as an attribute, so ``%`` needs no escaping)."""
    cfg = Config(str(HERE / "alembic.ini"))
    cfg.set_main_option("script_location", str(HERE / "migrations"))
    cfg.attributes["url"] = normalise_url(url)
    return cfg


def upgrade(url: str, revision: str = "head") -> None:
    """Upgrade the database at *url* to *revision*."""
    command.upgrade(alembic_config(url), revision)


def downgrade(url: str, revision: str = "base") -> None:
    """Downgrade the database at *url* to *revision*."""
    command.downgrade(alembic_config(url), revision)


def head_revision() -> str:
    """The newest revision this code knows."""
    head = ScriptDirectory.from_config(alembic_config("sqlite://")).get_current_head()
    if head is None:
        raise MigrationError("no migrations found")
    return head


def current_revision(engine: Engine) -> str | None:
    """The revision the database behind *engine* is at (``None`` when never migrated)."""
    with engine.connect() as conn:
        return MigrationContext.configure(conn).get_current_revision()


def ensure_at_head(url: str) -> str:
    """Upgrade *url* to head when it is behind; return the revision it is at afterwards."""
    engine = make_engine(url)
    try:
        if current_revision(engine) != head_revision():
            upgrade(url)
        rev = current_revision(engine)
    finally:
        engine.dispose()
    if rev != head_revision():
        raise MigrationError(f"database at {rev}, expected {head_revision()}")
    return rev
