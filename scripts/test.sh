#!/usr/bin/env bash
# The whole test suite on a fresh machine: set-up, lint and format check, layering contracts, type check
# (mypy, configured in pyproject.toml) and pytest (slow suites included). Extra arguments go to both
# pytest runs.
#
# mypy runs beside the core pytest process, its output kept and printed after it: on a fresh clone it
# analyses every package the tree imports (about 50 s of one CPU), while the core tests spend much of
# their time waiting on servers and child processes. Its exit status counts like a test process's.
#
# The viewer's tests run in a pytest process of their own: Qt draws through GLX under Xvfb, the core's
# renderer through moderngl's standalone EGL contexts, and Mesa cannot make a Qt GLX context current in
# a process that has already used EGL device contexts ("QOpenGLWidget: Failed to make context current").
#
# The core process runs in parallel (pytest-xdist): CACAD_TEST_WORKERS workers (default: one more than
# the CPU cores, at most 4: many core tests wait on servers and child processes, and on 2 cores a third
# worker took the core run from 12.1 to 9.5 minutes), each test file on one worker (--dist loadfile: a
# file's module fixtures, such as a running service, are built once), handed out in the order
# tests/conftest.py sets: files holding a slow test first, so that the workers finish together
# (--no-loadscope-reorder keeps that order). The viewer process runs the same way on at most 2 workers,
# each with its own Qt application and Xvfb display.
# CACAD_TEST_WORKERS=0 runs both in one process each; extra arguments (e.g. -n 0) come last and win.
#
# Under CI=true (as CI services set it) a test whose service is missing (the PostgreSQL server, an
# OpenGL context, Xvfb) fails instead of skipping (tests/services.py). Every test that leaves a process
# running fails, after the process is killed (tests/conftest.py).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
bash scripts/setup.sh
bash scripts/ensure-postgres.sh
export PATH="$root/.venv/bin:$PATH"
echo "== ruff"
ruff check .
ruff format --check .
echo "== import contracts"
lint-imports
reports="$root/.test-results"
rm -rf "$reports" && mkdir -p "$reports"
set +e
echo "== mypy (beside the core tests; its output follows them)"
mypy >"$reports/mypy.txt" 2>&1 &
mypy_pid=$!
echo "== pytest: core, service, drivers, tools"
workers="${CACAD_TEST_WORKERS:-$(($(nproc) + 1))}"
python -m pytest --ignore=tests/ui -n "$workers" --maxprocesses 4 --dist loadfile --no-loadscope-reorder \
  --junitxml="$reports/core.xml" "$@"
core=$?
wait "$mypy_pid"
typecheck=$?
echo "== mypy"
cat "$reports/mypy.txt"
echo "== pytest: viewer (own process, Qt on Xvfb)"
# Two workers at most (each starts its own Xvfb). A test stuck in a nested Qt event loop (a modal
# dialog) never returns to Python, so SIGALRM cannot stop it: the viewer's timeout uses a thread,
# which dumps the stacks and ends the worker instead of hanging the run.
python -m pytest tests/ui -n "$workers" --maxprocesses 2 --dist loadfile --no-loadscope-reorder \
  -o timeout_method=thread --junitxml="$reports/ui.xml" "$@"
ui=$?
set -e
echo "== all tests"
summary=0
python scripts/junit_summary.py "$reports/core.xml" "$reports/ui.xml" || summary=$?
if [ "$typecheck" -ne 0 ] || [ "$core" -ne 0 ] || [ "$ui" -ne 0 ] || [ "$summary" -ne 0 ]; then
  echo "FAILED (mypy exit $typecheck, core pytest exit $core, viewer pytest exit $ui)" >&2
  exit 1
fi
