"""Alembic environment shipped with the package (see db.migrate)."""
