"""Rules that keep the suite green on a loaded machine, checked on the test sources themselves:

* no test pauses with ``time.sleep``: it waits with a deadline (``tests.waiting.wait_until``), so a busy
  machine makes a test slower, never wrong, and an idle one never waits a guessed time; a pause that is
  itself the behaviour under test (a slow client, a device that answers late) is
  ``tests.waiting.pause``, in the files named here only;
* no test starts a process with ``subprocess.Popen`` / ``subprocess.run`` directly: it goes through
  ``tests.processes`` (``Child``, ``run``), which ends the process and what it started on every path;
* no ``pytest.importorskip`` of the project's own packages or of a declared dependency: a missing one is
  a broken install, which must fail, not skip;
* the fixtures that need a service (GL, PostgreSQL) skip through ``tests.services.service_missing``,
  which fails under ``CI=true``.
"""

from __future__ import annotations

import ast
import re
import tomllib
from pathlib import Path

import pytest

TESTS = Path(__file__).resolve().parent
REPO = TESTS.parent

#: Files that may call ``time.sleep``, each with its reason.
SLEEP_ALLOWED = {
    "tests/waiting.py": "wait_until's polling interval",
}
#: Files that may call ``tests.waiting.pause`` (a pause that plays part of the behaviour under test and
#: waits for nothing), each with what the pause plays.
PAUSE_ALLOWED = {
    "tests/api/test_serve_limits.py": "a slow client trickling header bytes, headers sent in two parts",
    "tests/api/test_image_bounds.py": "a slow decode holding its slot, so that concurrent uploads overlap",
    "tests/drivers/test_gloss_hid.py": "the fake hidapi device blocking for its read timeout",
}
#: Files that may start processes with ``subprocess`` directly, each with its reason.
SUBPROCESS_ALLOWED = {
    "tests/processes.py": "Child and run themselves",
    "tests/ui/conftest.py": "the viewer suite's Xvfb, started at import for the whole test run",
    "tests/test_processes.py": "a process deliberately left running, for the leftover check to find",
    "tests/soak/_fronts.py": "fronts killed at random (SIGKILL to their own process groups) and restarted",
    "tests/serve_process.py": "ServeProcess owns its `station serve` child: stop() interrupts then kills it",
}

#: The project's own top-level packages (setuptools' list plus the benchmarks and the tests).
PROJECT_PACKAGES = {"station", "db", "ui", "simulators", "bench", "tests"}


Sources = dict[str, ast.Module]


@pytest.fixture(scope="module")
def sources() -> Sources:
    """{path relative to the repository: syntax tree} of every Python file under tests/."""
    return {
        path.relative_to(REPO).as_posix(): ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
        for path in sorted(TESTS.rglob("*.py"))
    }


def _module_aliases(tree: ast.Module, module: str) -> tuple[set[str], dict[str, str]]:
    """Names under which *module* is imported, and {local name: attribute} of ``from module import``."""
    modules: set[str] = set()
    names: dict[str, str] = {}
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            modules |= {a.asname or a.name for a in node.names if a.name == module}
        elif isinstance(node, ast.ImportFrom) and node.module == module:
            names |= {a.asname or a.name: a.name for a in node.names}
    return modules, names


def _calls(tree: ast.Module, module: str, attrs: set[str]) -> list[tuple[int, str]]:
    """(line, ``module.attr``) of every call of ``module.attr`` for *attrs*, however imported."""
    modules, names = _module_aliases(tree, module)
    found = []
    for node in ast.walk(tree):
        if not isinstance(node, ast.Call):
            continue
        func = node.func
        if isinstance(func, ast.Attribute) and isinstance(func.value, ast.Name):
            if func.value.id in modules and func.attr in attrs:
                found.append((node.lineno, f"{module}.{func.attr}"))
        elif isinstance(func, ast.Name) and names.get(func.id) in attrs:
            found.append((node.lineno, f"{module}.{names[func.id]}"))
    return found


def _declared_dependencies() -> set[str]:
    project = tomllib.loads((REPO / "pyproject.toml").read_text())["project"]
    specs = list(project["dependencies"]) + [
        d for group in project["optional-dependencies"].values() for d in group
    ]
    return {_normal(re.split(r"[\s<>=!~;\[]", spec, maxsplit=1)[0]) for spec in specs}


def _normal(name: str) -> str:
    return re.sub(r"[-_.]+", "-", name).lower()


def test_no_test_sleeps(sources: Sources) -> None:
    found = [
        f"{path}:{line}: {call}"
        for path, tree in sources.items()
        if path not in SLEEP_ALLOWED
        for line, call in _calls(tree, "time", {"sleep"})
    ]
    assert not found, "wait with tests.waiting.wait_until (a deadline), not a fixed sleep:\n" + "\n".join(
        found
    )


def test_no_test_starts_a_process_it_might_not_end(sources: Sources) -> None:
    starts = {"Popen", "run", "call", "check_call", "check_output"}
    found = [
        f"{path}:{line}: {call}"
        for path, tree in sources.items()
        if path not in SUBPROCESS_ALLOWED
        for line, call in _calls(tree, "subprocess", starts)
    ]
    assert not found, "start processes with tests.processes.Child or run:\n" + "\n".join(found)


def test_pauses_only_where_the_pause_is_the_behaviour(sources: Sources) -> None:
    """``tests.waiting.pause`` only in the files that :data:`PAUSE_ALLOWED` names with their reason."""
    found = [
        f"{path}:{line}: {call}"
        for path, tree in sources.items()
        if path not in PAUSE_ALLOWED
        for line, call in _calls(tree, "tests.waiting", {"pause"})
    ]
    assert not found, "wait with tests.waiting.wait_until (a deadline), not a pause:\n" + "\n".join(found)


def test_the_allowances_are_still_needed(sources: Sources) -> None:
    """An allowance whose file no longer does what it allows is removed (the rules only tighten)."""
    trees = sources
    stale = [p for p in SLEEP_ALLOWED if p not in trees or not _calls(trees[p], "time", {"sleep"})]
    stale += [p for p in PAUSE_ALLOWED if p not in trees or not _calls(trees[p], "tests.waiting", {"pause"})]
    stale += [
        p
        for p in SUBPROCESS_ALLOWED
        if p not in trees
        or not _calls(trees[p], "subprocess", {"Popen", "run", "call", "check_call", "check_output"})
    ]
    assert not stale, f"no longer needed, remove from the allowances: {stale}"


def test_no_importorskip_of_what_must_be_installed(sources: Sources) -> None:
    """The project's own packages and its declared dependencies (dev ones included, e.g. mypy) are
    imported plainly: missing, the test fails."""
    declared = _declared_dependencies()
    assert {"mypy", "numpy", "pytest"} <= declared  # the parse found the lists
    found = []
    for path, tree in sources.items():
        for node in ast.walk(tree):
            if not (isinstance(node, ast.Call) and node.args and isinstance(node.args[0], ast.Constant)):
                continue
            func = node.func
            name = (
                func.attr
                if isinstance(func, ast.Attribute)
                else func.id
                if isinstance(func, ast.Name)
                else ""
            )
            if name != "importorskip":
                continue
            top = str(node.args[0].value).split(".")[0]
            if top in PROJECT_PACKAGES or _normal(top) in declared:
                found.append(f"{path}:{node.lineno}: importorskip({node.args[0].value!r})")
    assert not found, "import these plainly:\n" + "\n".join(found)


def test_service_fixtures_fail_under_ci_instead_of_skipping() -> None:
    """The GL fixtures skip only through ``tests.services.service_missing`` (which fails under CI=true);
    a plain skip would let a CI machine without GL pass without drawing anything."""
    for conftest in (TESTS / "render" / "conftest.py", TESTS / "ui" / "conftest.py"):
        tree = ast.parse(conftest.read_text())
        calls = {ast.unparse(node.func) for node in ast.walk(tree) if isinstance(node, ast.Call)}
        assert "service_missing" in calls, conftest
        assert not calls & {"pytest.skip", "pytest.mark.skip", "pytest.mark.skipif"}, conftest


#: Endings of files the product or its tests make at run time (caches, arrays, renders of data files):
#: they are regenerated, never committed.
GENERATED_ENDINGS = (".npy", ".npz", ".pkl", ".sqlite", ".db")


def test_no_generated_file_or_option_named_folder_is_tracked() -> None:
    """A prefilter cache once landed in the repository under a folder named ``--help`` (a benchmark took
    the option for its cache folder): no tracked path has a part that starts with ``-``, and no tracked
    file is a run-time cache."""
    from tests.processes import run

    listed = run(["git", "ls-files", "-z"], timeout=60, cwd=REPO).stdout.split("\0")
    bad = [
        name
        for name in listed
        if name
        and (any(part.startswith("-") for part in name.split("/")) or name.endswith(GENERATED_ENDINGS))
    ]
    assert not bad, "generated files are tracked:\n" + "\n".join(bad[:20])
