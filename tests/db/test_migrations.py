"""Every migration upgrades and downgrades on SQLite and PostgreSQL, and matches the models."""

from __future__ import annotations

from alembic.autogenerate import compare_metadata
from alembic.runtime.migration import MigrationContext
from alembic.script import ScriptDirectory
from sqlalchemy import inspect

import db.models  # noqa: F401
from db import migrate
from db.base import Base
from db.engine import make_engine

TABLES = {
    "instruments",
    "calibration_records",
    "panels",
    "measurements",
    "designs",
    "design_versions",
    "library_paints",
    "formulation_jobs",
    "analysis_results",
    "users",
    "api_tokens",
    "audit_events",
    "standards",
    "gloss_readings",
}


def _revisions() -> list[str]:
    script = ScriptDirectory.from_config(migrate.alembic_config("sqlite://"))
    return [rev.revision for rev in reversed(list(script.walk_revisions()))]


def test_each_revision_upgrades_and_downgrades(empty_database_url: str) -> None:
    engine = make_engine(empty_database_url)
    try:
        assert migrate.current_revision(engine) is None
        previous = "base"
        for rev in _revisions():
            migrate.upgrade(empty_database_url, rev)
            assert migrate.current_revision(engine) == rev
            migrate.downgrade(empty_database_url, previous)
            assert migrate.current_revision(engine) == (None if previous == "base" else previous)
            migrate.upgrade(empty_database_url, rev)
            previous = rev
        assert set(inspect(engine).get_table_names()) >= TABLES
        migrate.downgrade(empty_database_url, "base")
        assert set(inspect(engine).get_table_names()) == {"alembic_version"}
    finally:
        engine.dispose()


def test_head_matches_the_models(database_url: str) -> None:
    engine = make_engine(database_url)
    try:
        with engine.connect() as conn:
            diff = compare_metadata(
                MigrationContext.configure(conn, opts={"compare_type": True}), Base.metadata
            )
        assert diff == []
        assert migrate.current_revision(engine) == migrate.head_revision()
    finally:
        engine.dispose()


def test_constraints_follow_the_naming_convention(database_url: str) -> None:
    engine = make_engine(database_url)
    try:
        insp = inspect(engine)
        assert insp.get_pk_constraint("measurements")["name"] in ("pk_measurements", None)  # SQLite: unnamed
        fks = {fk["name"] for fk in insp.get_foreign_keys("measurements")}
        assert "fk_measurements_instrument_id_instruments" in fks
        uqs = {uq["name"] for uq in insp.get_unique_constraints("measurements")}
        assert {"uq_measurements_client_id", "uq_measurements_supersedes_id"} <= uqs
        checks = {ck["name"] for ck in insp.get_check_constraints("users")}
        assert "ck_users_role" in checks
    finally:
        engine.dispose()


def test_ensure_at_head_is_idempotent(empty_database_url: str) -> None:
    assert migrate.ensure_at_head(empty_database_url) == migrate.head_revision()
    assert migrate.ensure_at_head(empty_database_url) == migrate.head_revision()


def test_qc_standards_revision(empty_database_url: str) -> None:
    engine = make_engine(empty_database_url)
    try:
        migrate.upgrade(empty_database_url, "0005_token_expiry")
        assert "standards" not in inspect(engine).get_table_names()
        migrate.upgrade(empty_database_url, "0006_qc_standards")
        insp = inspect(engine)
        assert {c["name"] for c in insp.get_columns("standards")} == {
            "id",
            "job",
            "part",
            "measurement_id",
            "design_id",
            "notes",
            "created_at",
            "created_by_id",
        }
        assert {"ck_standards_one_reference", "ck_standards_part"} <= {
            ck["name"] for ck in insp.get_check_constraints("standards")
        }
        assert "uq_standards_job_part" in {uq["name"] for uq in insp.get_unique_constraints("standards")}
        assert {fk["referred_table"] for fk in insp.get_foreign_keys("standards")} == {
            "measurements",
            "designs",
            "users",
        }
        migrate.downgrade(empty_database_url, "0005_token_expiry")
        assert "standards" not in inspect(engine).get_table_names()
    finally:
        engine.dispose()
