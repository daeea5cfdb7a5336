"""Alembic revisions (dated file names; batch mode for SQLite)."""
