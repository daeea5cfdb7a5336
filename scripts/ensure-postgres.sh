#!/usr/bin/env bash
# Make sure the PostgreSQL server the database tests use (127.0.0.1:5432) is up; start it when it is
# installed but stopped (waiting up to CACAD_POSTGRES_START_S seconds, default 120: a loaded machine
# starts it slowly); fail loudly when it cannot be reached. Set CACAD_SKIP_POSTGRES=1 to skip (under
# CI=true the PostgreSQL tests then fail rather than skip).
set -uo pipefail
[ "${CACAD_SKIP_POSTGRES:-0}" = "1" ] && { echo "postgres: skipped (CACAD_SKIP_POSTGRES=1)"; exit 0; }
reachable() { (exec 3<>/dev/tcp/127.0.0.1/5432) 2>/dev/null; }
if reachable; then echo "postgres: reachable at 127.0.0.1:5432"; exit 0; fi
if command -v pg_ctlcluster >/dev/null 2>&1 && [ -d /etc/postgresql ]; then
  for v in /etc/postgresql/*; do
    pg_ctlcluster --skip-systemctl-redirect "$(basename "$v")" main start 2>/dev/null || true
  done
  deadline=$((SECONDS + ${CACAD_POSTGRES_START_S:-120}))
  while [ "$SECONDS" -lt "$deadline" ]; do reachable && { echo "postgres: started"; exit 0; }; sleep 0.2; done
fi
echo "postgres: FAILED: no server at 127.0.0.1:5432 and none could be started" >&2
exit 1
