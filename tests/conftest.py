"""Root test configuration shared by every suite.

Suites keep their own fixtures in ``tests/<area>/conftest.py``. Qt runs on the offscreen platform
unless a suite (the viewer's GL tests under Xvfb) sets another.

The suite runs in parallel (pytest-xdist, ``scripts/test.sh``): every pytest process (worker) has its
own temporary folders (``tmp_path``), its own disk caches (below), its own throwaway PostgreSQL
databases (``tests/db/_fixtures.py``), free loopback ports and, in the viewer suite, its own Xvfb display.

No test leaves a process running: after each test, a child process of this pytest process that was not
there before the test (and has not ended within ``LEFTOVER_GRACE_S``) is killed with its process group
and the test fails naming it. Tests start processes through ``tests.processes`` (``Child``, ``run``),
which end them on every path; they wait with ``tests.waiting.wait_until``, never a fixed sleep.
"""

from __future__ import annotations

import os
import signal
from collections.abc import Iterator
from pathlib import Path

import pytest

from tests.processes import children_of_this_process, end_leftovers

os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")

# Ctrl-C reaches the product's processes the tests start as it reaches a user's: a runner started in the
# background of a non-interactive shell (``nohup … &``) ignores SIGINT, every process it starts inherits
# that, and the tests of Ctrl-C (a watcher, a long command, the soak's fronts) then wait in vain. A handler
# set here is reset to the default in each child at its exec; an ignored signal would stay ignored.
if signal.getsignal(signal.SIGINT) is signal.SIG_IGN:
    signal.signal(signal.SIGINT, signal.default_int_handler)

REPO = Path(__file__).resolve().parents[1]
SHARED = REPO.parent / "shared"

#: Seconds a process a test has already told to stop gets to go before it counts as left running.
LEFTOVER_GRACE_S = 5.0


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """Run the files holding a ``slow`` test first, then the others by their number of tests (most
    first); the tests of one file stay together and in their order.

    ``scripts/test.sh`` hands whole files to the workers in this order (``--dist loadfile
    --no-loadscope-reorder``), so the long files start early and the last ones handed out are short:
    the workers finish together. (xdist's own order, by number of tests alone, left files of a few long
    tests, such as the soak, to the end, where one worker ran them while the other had nothing left.)
    """
    files: dict[str, list[pytest.Item]] = {}
    for item in items:
        files.setdefault(item.nodeid.split("::", 1)[0], []).append(item)

    def order(tests: list[pytest.Item]) -> tuple[bool, int]:
        return (not any(t.get_closest_marker("slow") for t in tests), -len(tests))

    items[:] = [item for tests in sorted(files.values(), key=order) for item in tests]


@pytest.fixture(autouse=True)
def _no_process_left() -> Iterator[None]:
    """Fail a test that leaves a child process running (after killing it): a leaked process would
    otherwise hold files and ports, and break a later, unrelated test when its ``Popen`` is collected
    (``ResourceWarning`` is an error in this suite). Processes of wider-scoped fixtures (a module's
    service, the viewer suite's Xvfb) were started before this fixture's first look and are not
    counted."""
    before = set(children_of_this_process())
    yield
    left = end_leftovers(before, LEFTOVER_GRACE_S)
    if left:
        listed = "; ".join(f"pid {pid}: {cmd[:200]}" for pid, cmd in sorted(left.items()))
        pytest.fail(f"the test left {len(left)} process(es) running (now killed): {listed}", pytrace=False)


@pytest.fixture(scope="session", autouse=True)
def _private_caches(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Path]:
    """The product's disk caches in this pytest process's own temporary folder.

    ``$STATION_CACHE_DIR`` (the demo library, ``station.formulate.demo``) and ``$CACAD_CACHE_DIR``
    (prefiltered cube maps, ``station.render.envcache``) otherwise default to folders under ``$HOME``,
    which parallel workers and other checkouts would share (the demo library is written through one
    fixed temporary name, so two processes generating it at once would write the same file). A worker
    generates the demo library once (about 4 s). Subprocesses inherit the variables.
    """
    root = tmp_path_factory.mktemp("cache")
    patch = pytest.MonkeyPatch()
    patch.setenv("STATION_CACHE_DIR", str(root / "station"))
    patch.setenv("CACAD_CACHE_DIR", str(root / "cacad"))
    yield root
    patch.undo()


@pytest.fixture(scope="session")
def bright_silver():
    """The shared bright aluminium silver (L*15 = 125, flop L* 38, travel 65°, 90 GU) of every package's
    ``test_bright_silver.py``: ``station.model.examples.BRIGHT_SILVER``."""
    from station.model.examples import BRIGHT_SILVER

    return BRIGHT_SILVER


@pytest.fixture(scope="session")
def shared_dir() -> Path:
    """The ../shared folder beside the checkout (skips when absent)."""
    if not SHARED.is_dir():
        pytest.skip(f"../shared not found at {SHARED}")
    return SHARED


@pytest.fixture(scope="session")
def hdri_files(shared_dir: Path) -> list[Path]:
    """Every photographed HDR environment in ../shared/data/hdri (skips when there are none)."""
    folder = shared_dir / "data" / "hdri"
    files = sorted(folder.glob("*.hdr")) + sorted(folder.glob("*.exr")) if folder.is_dir() else []
    if not files:
        pytest.skip(f"no HDR environments in {folder}")
    return files
