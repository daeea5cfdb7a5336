"""Module-level state: every process-wide cache and registry is listed here with the reason it is safe.

CONTRIBUTING.md ("No module-level mutable state") allows two kinds of module-level state and no other:

* a ``functools.cache`` / ``lru_cache`` on a pure function of hashable, immutable arguments, whose
  result the callers never modify (the model's caches return frozen dataclasses, tuples, read-only
  arrays or read-only mappings: :func:`test_model_caches_return_read_only_values`);
* a process-wide registry guarded by a lock, where the state *is* the process's (a serial port opened
  once per process; matplotlib's non-thread-safe pyplot; numba's one compilation).

Every ``.py`` file of ``station/``, ``db/``, ``ui/`` and ``simulators/`` (frozen migrations excepted)
is parsed with :mod:`ast`. A module-level function decorated with a cache, a module-level empty
container or mutable constructor (``set()``, ``{}``, ``dict()``, ``threading.Lock()`` …) or a ``global``
statement that is not in :data:`ALLOWED` fails the test, and so does an entry of :data:`ALLOWED` that no
longer exists. Non-empty literal tables (``GU_MAX = {20: 2000.0, …}``) are constants and not listed.
The checker is fed a synthetic source to show it can fail.
"""

from __future__ import annotations

import ast
import dataclasses
from pathlib import Path
from types import MappingProxyType

import numpy as np

REPO = Path(__file__).resolve().parents[1]
ROOTS = ("station", "db", "ui", "simulators")
FROZEN = ("db/migrations/versions",)

#: "path:name" → why it is safe to share across the process.
ALLOWED: dict[str, str] = {
    # pure functions of immutable arguments, read-only results (the model)
    "station/model/gloss.py:_geometry_nodes": "gloss-meter aperture quadrature per geometry; read-only mapping",
    "station/model/gloss.py:lobe_from_gloss": "GU → frozen SpecularLobe",
    "station/model/gloss.py:coat_from_gloss": "GU → frozen CoatLobes",
    "station/model/lobe.py:_table": "the forward meter's GU ⇄ exponent table; read-only arrays",
    "station/model/spectra.py:_weighting_factors": "ASTM E308 weights per illuminant/observer; read-only",
    "station/model/fresnel.py:fresnel_diffuse_reflectance": "F_dr,ext(n): a float per refractive index",
    # pure functions, data shipped with the product, loaded once
    "station/analysis/gamut.py:_pointer_hull": "Pointer's gamut hull (published data)",
    "station/formulate/effect_optics.py:colorant_data": "the shipped colorant data file, parsed",
    "station/formulate/effect_optics.py:_hemispherical_film": "a thin film's hemispherical reflectance (pure function of a frozen film)",
    "station/formulate/colorants.py:_flake_table": "flake reflectance table per (database, angle tuple)",
    "station/formulate/colorants.py:default_database": "the shipped colorant database, built once",
    "station/formulate/colorants.py:_tristimulus": "linear tristimulus weights of the product's own Lab",
    "station/formulate/lines.py:_data": "the shipped toner-line data file, parsed",
    "station/formulate/demo.py:demo_library": "the synthetic 6000-paint demo library (seeded)",
    "station/formulate/munsell.py:munsell_library": "Munsell renotation library (colour-science's data)",
    "station/render/design_db.py:design_database": "the 40 built-in designs (deterministic)",
    "station/render/lobe_fit.py:fit_problem": "least-squares problem per (basis, gloss form, target, fall-off)",
    "station/render/lobes.py:sample_geometries": "the fixed fitting geometries",
    "station/render/lobes.py:_basis_text": "the shipped lobe basis file",
    "station/render/lobes.py:default_basis": "the shipped lobe basis",
    "station/render/ground.py:height_columns": "a closed shape's height columns per shape name; read-only arrays",
    "station/render/ground.py:occlusion_map": "the ground's occlusion map per shape and ground (bounded LRU); read-only",
    "simulators/gloss.py:reference_coat": "black-glass reference lobe per (GU, geometry)",
    "ui/models/view.py:paint_weights": "lobe weights of a frozen design on the shipped basis",
    "ui/models/view.py:_file_environment": "an environment file, keyed by path and modification time",
    "ui/models/view.py:_environment_basis": "prefiltered basis per (environment, size)",
    # compiled SQL statements per dialect / chain (pure functions of a name)
    "station/ingest/store.py:_measurement_insert": "the compiled measurement INSERT per SQL dialect",
    "db/chain.py:_chain_insert": "the compiled INSERT of one tamper-evident chain",
    "db/chain.py:_pg_insert": "the PostgreSQL INSERT text of a chain's columns (strings in, a string out)",
    "db/chain.py:_bind_processors": "SQLAlchemy's bind processors per dialect, chain and columns (bounded LRU)",
    # compilation, once per process
    "station/render/ground.py:_LOOPS": "numba's compilation of the ground's occlusion loop (station.jit)",
    "station/render/prefilter_kernels.py:_LOOPS": "numba's compilation of the NumPy prefilter's loops (station.jit)",
    "station/formulate/snap/kernel.py:_LOOPS": "numba's compilation of the ColorSnap walk (ADR 0002, station.jit)",
    # process-wide registries, the process's own state
    "station/drivers/transport.py:_OWNERS": "addresses open in this process: a port is opened once",
    "station/drivers/transport.py:_OWNERS_LOCK": "guards _OWNERS",
    "station/api/services/analyses.py:_PLOT_LOCK": "matplotlib's pyplot is not thread-safe",
    "ui/models/view.py:_READY": "environments whose prefiltered maps exist on disk (key: path, mtime)",
}

_MUTABLE_CALLS = {
    "set",
    "dict",
    "list",
    "bytearray",
    "defaultdict",
    "collections.defaultdict",
    "OrderedDict",
    "collections.OrderedDict",
    "deque",
    "collections.deque",
    "threading.Lock",
    "threading.RLock",
    "Lock",
    "RLock",
    "weakref.WeakValueDictionary",
    "weakref.WeakKeyDictionary",
    "CompiledLoops",  # station.jit: a lock and the compiled functions, filled on first use
}


def _is_cache(decorator: ast.expr) -> bool:
    text = ast.unparse(decorator.func if isinstance(decorator, ast.Call) else decorator)
    return text.split(".")[-1] in {"cache", "lru_cache"}


def _is_mutable(value: ast.expr) -> bool:
    if isinstance(value, (ast.Dict, ast.List, ast.Set)):
        return not (value.keys if isinstance(value, ast.Dict) else value.elts)  # an empty container
    if isinstance(value, ast.Call):
        return ast.unparse(value.func) in _MUTABLE_CALLS
    return False


def module_state(source: str) -> list[str]:
    """Names of the module-level caches, mutable containers and ``global`` rebindings in *source*."""
    tree = ast.parse(source)
    found: list[str] = []
    for node in tree.body:
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)) and any(
            _is_cache(d) for d in node.decorator_list
        ):
            found.append(node.name)
        elif (
            isinstance(node, (ast.Assign, ast.AnnAssign))
            and node.value is not None
            and _is_mutable(node.value)
        ):
            targets = node.targets if isinstance(node, ast.Assign) else [node.target]
            found += [ast.unparse(t) for t in targets]
    found += [f"global {name}" for n in ast.walk(tree) if isinstance(n, ast.Global) for name in n.names]
    return found


def _tree_state() -> set[str]:
    out: set[str] = set()
    for root in ROOTS:
        for path in sorted((REPO / root).rglob("*.py")):
            rel = path.relative_to(REPO).as_posix()
            if rel.startswith(FROZEN):
                continue
            out |= {f"{rel}:{name}" for name in module_state(path.read_text(encoding="utf-8"))}
    return out


def test_every_module_level_cache_and_registry_is_listed() -> None:
    found = _tree_state()
    assert sorted(found - ALLOWED.keys()) == [], "module-level state not listed in tests/test_module_state.py"
    assert sorted(ALLOWED.keys() - found) == [], "listed module-level state that no longer exists"


def test_the_checker_finds_planted_state() -> None:
    planted = """
import functools, threading
from functools import lru_cache
TABLE = {20: 1.0}
_SEEN = set()
_BY_ID: dict[str, int] = {}
_LOCK = threading.Lock()
@functools.cache
def a(x): return x
@lru_cache(maxsize=4)
def b(x): return x
def c():
    global TABLE
"""
    assert module_state(planted) == ["_SEEN", "_BY_ID", "_LOCK", "a", "b", "global TABLE"]


def _read_only(value: object) -> bool:
    if isinstance(value, np.ndarray):
        return not value.flags.writeable
    if isinstance(value, (float, int, str, np.floating)):
        return True
    if isinstance(value, tuple):
        return all(_read_only(v) for v in value)
    if isinstance(value, MappingProxyType):
        return all(_read_only(v) for v in value.values())
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        frozen = type(value).__dataclass_params__.frozen  # type: ignore[attr-defined]
        return frozen and all(_read_only(getattr(value, f.name)) for f in dataclasses.fields(value))
    return False


def test_model_caches_return_read_only_values() -> None:
    from station.model import fresnel, gloss, lobe, spectra
    from station.model.colorimetry import OBSERVER_10

    results = {
        "_geometry_nodes": gloss._geometry_nodes(60),
        "lobe_from_gloss": gloss.lobe_from_gloss(60.0),
        "coat_from_gloss": gloss.coat_from_gloss(60.0),
        "_table": lobe._table(),
        "_weighting_factors": spectra._weighting_factors("D65", OBSERVER_10),
        "fresnel_diffuse_reflectance": fresnel.fresnel_diffuse_reflectance(1.5),
    }
    assert {name for name in results} == {
        key.split(":")[1] for key in ALLOWED if key.startswith("station/model/")
    }, "a model cache without a check here"
    for name, value in results.items():
        assert _read_only(value), name
