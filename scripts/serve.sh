#!/usr/bin/env bash
# The main job on a fresh machine: set-up, then the workstation service with simulated instruments
# on the embedded SQLite database. Extra arguments go to `station serve`.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
bash scripts/setup.sh
export PATH="$root/.venv/bin:$PATH"
if station serve --help >/dev/null 2>&1; then
  exec station serve "$@"
fi
# Until the service exists: the end-to-end demo of the appearance model.
exec station demo "$@"
