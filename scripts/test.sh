#!/usr/bin/env bash
# The whole test suite on a fresh machine: set-up, lint, layering contracts, then pytest
# (slow suites included). Extra arguments go to pytest.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
bash scripts/setup.sh
bash scripts/ensure-postgres.sh
export PATH="$root/.venv/bin:$PATH"
echo "== ruff"
ruff check .
echo "== import contracts"
lint-imports
echo "== pytest"
exec python -m pytest "$@"
