#!/usr/bin/env bash
# PostgreSQL for a deployment: two roles and one database.
#   owner   (CACAD_PG_OWNER, default cacad_owner)    owns the database and the tables; runs migrations.
#   service (CACAD_PG_SERVICE, default cacad_service) what `station serve` connects as: reads and writes
#           rows, but cannot TRUNCATE, ALTER, DROP or DISABLE the append-only triggers, cannot UPDATE
#           or DELETE measurements, audit events, record events and gloss readings at all, and can move
#           a chain head (ledger_heads) only onto the chain's new last row, linked from the old head
#           (the owner's trigger checks the link; see db/chain.py).
# Creates what is missing, migrates the database to head as the owner (`station db upgrade`), then
# (re)grants the service role. Idempotent: run it again after every upgrade of the code.
# Environment: CACAD_PG_HOST (127.0.0.1), CACAD_PG_PORT (5432), CACAD_PG_SUPERUSER (postgres; the
# connection must be allowed by pg_hba, e.g. peer or PGPASSWORD), CACAD_PG_DB (cacad),
# CACAD_PG_OWNER_PASSWORD / CACAD_PG_SERVICE_PASSWORD (set when given). Prints the two URLs.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
host="${CACAD_PG_HOST:-127.0.0.1}"
port="${CACAD_PG_PORT:-5432}"
superuser="${CACAD_PG_SUPERUSER:-postgres}"
db="${CACAD_PG_DB:-cacad}"
owner="${CACAD_PG_OWNER:-cacad_owner}"
service="${CACAD_PG_SERVICE:-cacad_service}"
owner_pw="${CACAD_PG_OWNER_PASSWORD:-}"
service_pw="${CACAD_PG_SERVICE_PASSWORD:-}"
python="${PYTHON:-python3}"
[ -x "$root/.venv/bin/python" ] && [ -z "${PYTHON:-}" ] && python="$root/.venv/bin/python"

psql_as_super() { # $1 = database; SQL on stdin
  psql -X -q -h "$host" -p "$port" -U "$superuser" -d "$1" -v ON_ERROR_STOP=1 \
    -v owner="$owner" -v service="$service" -v db="$db" -v owner_pw="$owner_pw" -v service_pw="$service_pw"
}

psql_as_super postgres <<'SQL'
SELECT format('CREATE ROLE %I LOGIN NOSUPERUSER NOCREATEDB NOCREATEROLE', :'owner')
 WHERE NOT EXISTS (SELECT 1 FROM pg_roles WHERE rolname = :'owner') \gexec
SELECT format('CREATE ROLE %I LOGIN NOSUPERUSER NOCREATEDB NOCREATEROLE', :'service')
 WHERE NOT EXISTS (SELECT 1 FROM pg_roles WHERE rolname = :'service') \gexec
SELECT format('ALTER ROLE %I PASSWORD %L', :'owner', :'owner_pw') WHERE :'owner_pw' <> '' \gexec
SELECT format('ALTER ROLE %I PASSWORD %L', :'service', :'service_pw') WHERE :'service_pw' <> '' \gexec
SELECT format('CREATE DATABASE %I OWNER %I', :'db', :'owner')
 WHERE NOT EXISTS (SELECT 1 FROM pg_database WHERE datname = :'db') \gexec
SELECT format('REVOKE ALL ON DATABASE %I FROM PUBLIC', :'db') \gexec
SELECT format('GRANT CONNECT, TEMPORARY ON DATABASE %I TO %I', :'db', :'service') \gexec
SQL

psql_as_super "$db" <<'SQL'
SELECT format('ALTER SCHEMA public OWNER TO %I', :'owner') \gexec
REVOKE ALL ON SCHEMA public FROM PUBLIC;
SELECT format('GRANT USAGE ON SCHEMA public TO %I', :'service') \gexec
SQL

enc() { "$python" -c 'import sys, urllib.parse as u; print(u.quote(sys.argv[1], safe=""))' "$1"; }
url_of() { # $1 = role, $2 = password
  local auth; auth="$(enc "$1")"; [ -n "$2" ] && auth="$auth:$(enc "$2")"
  echo "postgresql://$auth@$host:$port/$db"
}
owner_url="$(url_of "$owner" "$owner_pw")"
service_url="$(url_of "$service" "$service_pw")"
(cd "$root" && PYTHONPATH="$root${PYTHONPATH:+:$PYTHONPATH}" "$python" -m station.cli db upgrade --database "$owner_url" >/dev/null)

psql_as_super "$db" <<'SQL'
SELECT format('REVOKE ALL ON ALL TABLES IN SCHEMA public FROM %I', :'service') \gexec
SELECT format('GRANT SELECT, INSERT, UPDATE, DELETE ON ALL TABLES IN SCHEMA public TO %I', :'service') \gexec
SELECT format('REVOKE UPDATE, DELETE ON measurements, audit_events, record_events, gloss_readings FROM %I', :'service') \gexec
SELECT format('REVOKE DELETE ON ledger_heads FROM %I', :'service') \gexec
SELECT format('REVOKE INSERT, UPDATE, DELETE ON alembic_version FROM %I', :'service') \gexec
SELECT format('GRANT USAGE, SELECT ON ALL SEQUENCES IN SCHEMA public TO %I', :'service') \gexec
SQL
echo "owner (migrations):   ${owner_url//:$(enc "${owner_pw:-x}")@/:***@}"
echo "service (CACAD_DATABASE_URL for station serve): ${service_url//:$(enc "${service_pw:-x}")@/:***@}"
