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


def test_measurement_texture_revision_keeps_old_rows_hashes(empty_database_url: str) -> None:
    """Revision 0008: rows chained before it read 45° and no texture, and keep their hashes."""
    import datetime as dt
    import uuid

    from sqlalchemy import column, select, table
    from sqlalchemy.pool import NullPool

    from db import chain, chain_audit

    url = empty_database_url
    migrate.upgrade(url, "0007_gloss_readings")
    engine = make_engine(url, poolclass=NullPool)
    at = dt.datetime(2026, 11, 30, 8, 0, tzinfo=dt.UTC)
    try:
        with engine.begin() as conn:  # a measurement as revision 0007 wrote it, on the chain
            instruments = table(
                "instruments",
                column("id"),
                column("serial"),
                column("model"),
                column("kind"),
                column("created_at"),
            )
            inst = conn.execute(
                instruments.insert()
                .values(serial="SN-OLD", model="MA-T12", kind="multiangle", created_at=at)
                .returning(instruments.c.id)
            ).scalar_one()
            row = {
                "client_id": uuid.uuid4(),
                "panel_id": None,
                "instrument_id": inst,
                "calibration_id": None,
                "operator": "qa",
                "measured_at": at,
                "received_at": at,
                "illuminant": "D65",
                "observer": "CIE 1964 10 Degree Standard Observer",
                "geometries_deg": [15.0, 45.0, 110.0],
                "lab": [[80.0, -1.0, -20.0], [50.0, 0.0, -10.0], [30.0, 1.0, -5.0]],
                "wavelengths_nm": None,
                "spectra": None,
                "gloss_gu": None,
                "gloss_geometry_deg": None,
                "payload_sha256": "a" * 64,
                "supersedes_id": None,
                "correction_reason": None,
                "created_by_id": None,
            }
            head = chain.lock_head(conn, "measurements")
            old_hash, link = chain.seal("measurements", head, row)
            tbl = chain.chain_table("measurements", optional=False)
            conn.execute(tbl.insert().values(**row, row_sha256=old_hash, chain_sha256=link))
            chain.advance(conn, "measurements", head, link, at)
        cols = {c["name"] for c in inspect(engine).get_columns("measurements")}
        assert "illumination_deg" not in cols and "texture" not in cols
        migrate.upgrade(url, "0008_measurement_texture")
        cols = {c["name"] for c in inspect(engine).get_columns("measurements")}
        assert {"illumination_deg", "texture"} <= cols
        with engine.connect() as conn:
            m = conn.execute(select(chain.chain_table("measurements"))).mappings().one()
            assert (m["illumination_deg"], m["texture"]) == (45.0, None)
            assert m["row_sha256"] == old_hash == chain.payload_sha256("measurements", m)
            assert [v.broken for v in chain_audit.verify(conn)] == [None, None]
        # a 15° block with texture hashes its two values: changing either changes the hash
        lit15 = dict(row, illumination_deg=15.0, texture=[{"vendor": "X", "name": "sparkle", "geometry": "",
                                                           "value": 1.5}])  # fmt: skip
        hashes = {
            chain.payload_sha256("measurements", r)
            for r in (row, lit15, dict(lit15, illumination_deg=45), dict(lit15, texture=None))
        }
        assert (
            len(hashes) == 4
            and chain.payload_sha256("measurements", dict(row, illumination_deg=45)) == old_hash
        )
        migrate.downgrade(url, "0007_gloss_readings")
        cols = {c["name"] for c in inspect(engine).get_columns("measurements")}
        assert "illumination_deg" not in cols and "texture" not in cols
    finally:
        engine.dispose()
