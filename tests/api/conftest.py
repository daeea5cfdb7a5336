from tests.db._fixtures import database_url, empty_database_url, pg_server, pg_url  # noqa: F401
