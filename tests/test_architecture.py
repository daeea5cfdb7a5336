"""Architecture: the domain's Lab bounds and standard geometry sets are written in one place only.

Every ``.py`` file of ``station/``, ``ui/`` and ``db/`` (frozen migrations excepted) is parsed with
:mod:`ast`; outside ``station/model/domain.py`` none may contain

* a tuple or list of numbers equal to a standard geometry set (15/45/110, 25/45/75, the 5-angle set,
  ASTM E2194 −15/15/25/45/75/110);
* a comparison of an L*/a*/b*-named expression (``L``, ``lab``, ``face[0]``, ``abs(a)`` …) with a
  numeric Lab bound (100, 150, 200, or their negatives);
* a call with a Lab channel name (``"L"``, ``"a"``, ``"b"``) or a Lab-named first argument and such a
  bound (``_num(e, "L", where, 0.0, 150.0)``, ``np.clip(lab, 0.0, 150.0)``);
* a pydantic ``Field(ge=…, le=…)`` with a literal Lab bound (±150 or ±200);
* a dict keyed by ``"L"``/``"a"``/``"b"`` holding literal ranges (a copied ``LAB_RANGES``);
* a message (string constant outside docstrings) stating a Lab range, such as ``"0..100"`` beside
  ``L*`` or ``"0 <= L* <= 200"``.

The checker is fed synthetic sources with copied bounds to show it can fail.
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest

from station.drivers.families import FAMILY_NAMES
from station.model.colorimetry import REC709_LUMINANCE
from station.model.domain import (
    ANGLES_3,
    ANGLES_3_ALT,
    ANGLES_5,
    ANGLES_6,
    BOOTH_ILLUMINANTS,
    DELTA_E_COMPUTED,
    DELTA_E_ENVIRONMENT,
    DELTA_E_METHOD_NAMES,
    PAINT_TYPES,
    SNAP_METRICS,
    TOLERANCE_AGGREGATIONS,
)

REPO = Path(__file__).resolve().parents[1]
DOMAIN = REPO / "station" / "model" / "domain.py"
ROOTS = ("station", "ui", "db")
FROZEN = ("db/migrations/versions",)

GEOMETRY_SETS = {tuple(float(a) for a in s) for s in (ANGLES_3, ANGLES_3_ALT, ANGLES_5, ANGLES_6)}
BOUND_VALUES = {100.0, 150.0, 200.0}
CHANNEL_NAMES = {"L", "a", "b", "A", "B"}
_L_NAME = re.compile(r"^(L\d*|L_.*|.*_L|l_star|lstar|a_star|b_star|lightness)$")
_LAB_TOKEN = {"lab", "labs"}
_RANGE_TEXT = re.compile(
    r"(L\*[^\"']{0,30}?-?\d+(\.\d+)?\s*(\.\.|–|—|to)\s*-?\d+)"  # L* … 0..100, L* 0–150
    r"|(-?\d+(\.\d+)?\s*<=?\s*[Lab]\*\s*<=?\s*-?\d+)"  # 0 <= L* <= 200
    r"|(\|[ab]\*\|[^\"']{0,12}?(<=|≤)\s*\d+)",  # |a*| <= 200
)


def _number(node: ast.AST) -> float | None:
    """The value of a numeric literal (with unary minus), else None."""
    if isinstance(node, ast.UnaryOp) and isinstance(node.op, ast.USub):
        v = _number(node.operand)
        return None if v is None else -v
    if (
        isinstance(node, ast.Constant)
        and isinstance(node.value, (int, float))
        and not isinstance(node.value, bool)
    ):
        return float(node.value)
    return None


def _is_bound(node: ast.AST) -> bool:
    v = _number(node)
    return v is not None and abs(v) in BOUND_VALUES


def _identifier(node: ast.AST) -> str | None:
    if isinstance(node, ast.Name):
        return node.id
    if isinstance(node, ast.Attribute):
        return node.attr
    return None


def _lab_named(name: str | None) -> bool:
    if not name:
        return False
    return bool(_L_NAME.match(name)) or bool(_LAB_TOKEN & set(name.lower().split("_")))


def _lab_ish(node: ast.AST) -> bool:
    """An expression naming a Lab quantity: ``L``, ``lab``, ``face_lab``, ``face[0]``, ``abs(L2)``."""
    if isinstance(node, ast.Call) and _identifier(node.func) in {"abs", "float"} and node.args:
        return _lab_ish(node.args[0])
    if isinstance(node, ast.Subscript):
        base = _identifier(node.value)
        if base in {"face", "flop"} and _number(node.slice) == 0.0:
            return True
        return _lab_ish(node.value)
    return _lab_named(_identifier(node))


def _docstrings(tree: ast.AST) -> set[int]:
    ids: set[int] = set()
    for node in ast.walk(tree):
        if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef)):
            body = getattr(node, "body", [])
            if body and isinstance(body[0], ast.Expr) and isinstance(body[0].value, ast.Constant):
                ids.add(id(body[0].value))
    return ids


def _schema_examples(tree: ast.AST) -> set[int]:
    """Nodes inside ``json_schema_extra=``/``examples=`` arguments: documented sample data, not rules."""
    ids: set[int] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.keyword) and node.arg in {"json_schema_extra", "examples"}:
            ids.update(id(n) for n in ast.walk(node.value))
    return ids


def violations(source: str, filename: str = "<source>") -> list[str]:
    """Every copied Lab bound or geometry list in *source*, as ``"file:line: what"``."""
    tree = ast.parse(source, filename)
    docs = _docstrings(tree) | _schema_examples(tree)
    found: list[str] = []

    def hit(node: ast.AST, what: str) -> None:
        found.append(f"{filename}:{getattr(node, 'lineno', 0)}: {what}")

    for node in ast.walk(tree):
        if id(node) in docs:
            continue
        if isinstance(node, (ast.Tuple, ast.List)):
            values = [_number(e) for e in node.elts]
            if values and None not in values and tuple(values) in GEOMETRY_SETS:
                hit(node, f"standard geometry set {tuple(values)} (use station.model.domain)")
        elif isinstance(node, ast.Compare):
            operands = [node.left, *node.comparators]
            if any(_is_bound(o) for o in operands) and any(_lab_ish(o) for o in operands):
                hit(node, "Lab bound compared with a literal (use station.model.domain.check_lab)")
        elif isinstance(node, ast.Call):
            name = _identifier(node.func)
            keywords = {k.arg: k.value for k in node.keywords if k.arg}
            if name == "Field":
                if any(
                    (n := _number(keywords[k])) is not None and abs(n) in {150.0, 200.0}
                    for k in ("ge", "le", "gt", "lt")
                    if k in keywords
                ):
                    hit(node, "pydantic Field with a literal Lab bound (use station.model.domain.LAB_RANGES)")
                continue
            args = list(node.args)
            channel_arg = any(isinstance(a, ast.Constant) and a.value in CHANNEL_NAMES for a in args)
            lab_arg = bool(args) and _lab_ish(args[0])
            if (channel_arg or lab_arg) and any(_is_bound(a) for a in args):
                hit(node, "Lab bound passed as a literal (use station.model.domain.LAB_RANGES)")
        elif isinstance(node, ast.Dict):
            keys = {k.value for k in node.keys if isinstance(k, ast.Constant) and isinstance(k.value, str)}
            if keys >= {"L"} and keys & {"a", "b"}:
                for v in node.values:
                    if (
                        isinstance(v, (ast.Tuple, ast.List))
                        and len(v.elts) == 2
                        and all(_number(e) is not None for e in v.elts)
                    ):
                        hit(node, "Lab ranges written as literals (use station.model.domain.LAB_RANGES)")
                        break
        elif isinstance(node, ast.JoinedStr):
            text = "".join(str(v.value) if isinstance(v, ast.Constant) else "{…}" for v in node.values)
            if _RANGE_TEXT.search(text):
                hit(node, f"Lab range written in a message: {text!r} (use domain.lab_accepted)")
        elif isinstance(node, ast.Constant) and isinstance(node.value, str) and id(node) not in docs:
            if _RANGE_TEXT.search(node.value):
                hit(node, f"Lab range written in a message: {node.value!r} (use domain.lab_accepted)")
    return found


def _sources() -> list[Path]:
    files = []
    for root in ROOTS:
        for path in sorted((REPO / root).rglob("*.py")):
            rel = path.relative_to(REPO).as_posix()
            if path == DOMAIN or any(rel.startswith(f) for f in FROZEN):
                continue
            files.append(path)
    return files


def test_lab_bounds_and_geometry_sets_live_only_in_the_domain_module() -> None:
    files = _sources()
    assert len(files) > 100  # the walk found the packages
    found = [v for p in files for v in violations(p.read_text(), p.relative_to(REPO).as_posix())]
    assert found == [], "\n".join(found)


@pytest.mark.parametrize(
    "source",
    [
        "ANGLES = (15.0, 45.0, 110.0)\n",
        "SETS = [[25, 45, 75]]\n",
        "A6 = (-15, 15, 25, 45, 75, 110)\n",
        "def f(L2):\n    if not 0.0 <= L2 <= 100.0:\n        raise ValueError('x')\n",
        "def f(face):\n    return face[0] <= 100.0\n",
        "def f(v):\n    return abs(lab[1]) > 150.0\n",
        "def f(e):\n    return _num(e, 'L', 'w', 0.0, 150.0)\n",
        "import numpy as np\nx = np.clip(target_lab, 0.0, 150.0)\n",
        "T = Annotated[float, Field(ge=-200.0, le=200.0)]\n",
        "R = {'L': (0.0, 150.0), 'a': (-200.0, 200.0), 'b': (-200.0, 200.0)}\n",
        "msg = f'L* would be {x}, outside 0..100'\n",
        "msg = '0 <= L* <= 200'\n",
    ],
)
def test_the_checker_finds_a_copied_bound(source: str) -> None:
    assert violations(source), source


@pytest.mark.parametrize(
    "source",
    [
        "ANGLES = (15.0, 45.0)\n",  # not a standard set
        "def f(label):\n    return label <= 100\n",  # 'label' is not Lab
        "def f(g):\n    return 0.0 <= g <= 100.0\n",  # gloss, not Lab
        "def f():\n    '''L* 0..100 in the thesis.'''\n",  # docstrings may explain ranges
        "x = Field(ge=1, le=100)\n",  # a page size
        "LAB = LAB_RANGES['L']\n",
        "M = ConfigDict(json_schema_extra={'examples': [{'angles_deg': [15.0, 45.0, 110.0]}]})\n",
    ],
)
def test_the_checker_leaves_other_numbers_alone(source: str) -> None:
    assert violations(source) == [], source


def _domain_constants() -> set[str]:
    """Upper-case module-level names that station/model/domain.py assigns (its limits and vocabulary)."""
    tree = ast.parse(DOMAIN.read_text())
    names: set[str] = set()
    for node in tree.body:
        targets = (
            node.targets
            if isinstance(node, ast.Assign)
            else [node.target]
            if isinstance(node, ast.AnnAssign)
            else []
        )
        for t in targets:
            for n in ast.walk(t):
                if isinstance(n, ast.Name) and n.id.isupper():
                    names.add(n.id)
    return names


def redefinitions(source: str, constants: set[str], where: str = "<source>") -> list[str]:
    """Module-level assignments in *source* that bind a name the domain module defines."""
    found = []
    for node in ast.parse(source).body:
        targets = (
            node.targets
            if isinstance(node, ast.Assign)
            else [node.target]
            if isinstance(node, ast.AnnAssign)
            else []
        )
        for t in targets:
            for n in ast.walk(t):
                if isinstance(n, ast.Name) and n.id in constants:
                    # A plain alias of the domain's own name (X = domain.X) is an import, not a copy.
                    value = getattr(node, "value", None)
                    if isinstance(value, (ast.Name, ast.Attribute)):
                        continue
                    found.append(
                        f"{where}:{node.lineno}: {n.id} redefined (import it from station.model.domain)"
                    )
    return found


def test_no_module_redefines_a_domain_constant() -> None:
    constants = _domain_constants()
    assert {"FACE_ANGLE_DEG", "L_MAX", "AB_MAX", "TRAVEL_MAX_DEG"} <= constants
    found = [
        v for p in _sources() for v in redefinitions(p.read_text(), constants, p.relative_to(REPO).as_posix())
    ]
    assert found == [], "\n".join(found)


def test_the_redefinition_check_can_fail() -> None:
    constants = _domain_constants()
    assert redefinitions("FACE_ANGLE_DEG = 15.0\n", constants)
    assert redefinitions("GLOSS_MIN_GU, GLOSS_MAX_GU = 0.0, 100.0\n", constants)
    assert (
        redefinitions("from station.model.domain import FACE_ANGLE_DEG\nX = FACE_ANGLE_DEG\n", constants)
        == []
    )


# -- one scan path ---------------------------------------------------------------------------------------
# Pairing a gloss reading with a colour reading, turning readings into ingest records and storing gloss rows
# happen in station/scan only (the drivers and ingest define the pieces). A front (the viewer, the service,
# the CLI) or any other module that measures an instrument itself, sorts readings into gloss and colour, or
# builds or stores their records has grown a second scan path: these checks fail on it.

SCAN_HOMES = ("station/scan/", "station/ingest/", "station/drivers/")
#: Names only the scan path uses: the reading → record conversions, the gloss geometry stored with colour,
#: the gloss writer.
SCAN_NAMES = frozenset(
    {"record_from_reading", "gloss_record_from_reading", "GLOSS_GEOMETRY_DEG", "store_gloss"}
)
#: Reading types whose isinstance test sorts a reading into gloss or colour.
READING_TYPES = frozenset({"GlossReading", "SpectralReading"})
#: (file, name) allowed outside the scan path, each with its reason.
SCAN_EXCEPTIONS = {
    # POST /qc/gloss stores a gloss record a client sent: no instrument is read and nothing is paired.
    ("station/api/services/qc.py", "store_gloss"),
}


def scan_copies(source: str, where: str = "<source>") -> list[str]:
    """Places in *source* (a module outside the scan path) that do the scan path's work themselves, by line."""
    found: list[tuple[int, str]] = []
    for node in ast.walk(ast.parse(source)):
        names: list[str] = []
        line = getattr(node, "lineno", 0)
        if isinstance(node, ast.ImportFrom):
            names = [a.name for a in node.names]
        elif isinstance(node, (ast.Name, ast.Attribute)):
            names = [_identifier(node) or ""]
        for name in names:
            if name in SCAN_NAMES and (where, name) not in SCAN_EXCEPTIONS:
                found.append((line, f"{where}:{line}: {name} outside station/scan (call station.scan)"))
        if not isinstance(node, ast.Call):
            continue
        func = node.func
        if isinstance(func, ast.Attribute) and func.attr == "measure" and not node.args and not node.keywords:
            what = "an instrument measured outside station/scan (station.scan.take)"
            found.append((node.lineno, f"{where}:{node.lineno}: {what}"))
        if isinstance(func, ast.Name) and func.id == "isinstance" and len(node.args) == 2:
            kinds = node.args[1].elts if isinstance(node.args[1], ast.Tuple) else [node.args[1]]
            if any(_identifier(k) in READING_TYPES for k in kinds):
                what = "a reading sorted into gloss or colour outside station/scan"
                found.append((node.lineno, f"{where}:{node.lineno}: {what}"))
    return [text for _line, text in sorted(found)]


def _scan_copies_under(root: Path) -> list[str]:
    found = []
    for top in ROOTS:
        for path in sorted((root / top).rglob("*.py")):
            rel = path.relative_to(root).as_posix()
            if rel.startswith(SCAN_HOMES) or any(rel.startswith(f) for f in FROZEN):
                continue
            found += scan_copies(path.read_text(), rel)
    return found


def test_only_the_scan_path_pairs_gloss_with_colour() -> None:
    assert (REPO / "station" / "scan" / "store.py").is_file()
    found = _scan_copies_under(REPO)
    assert found == [], "\n".join(found)


# The viewer's own scan as it was before station/scan existed: it measured both instruments, sorted the
# readings and built the record with the 60° gloss itself.
_PLANTED_VIEWER_SCAN = """
from station.drivers import GlossReading
from station.ingest.records import GLOSS_GEOMETRY_DEG


def scan(session, panel):
    gloss = session.gloss_meter.measure()
    if not isinstance(gloss, GlossReading):
        raise ValueError("gloss_device")
    reading = session.instrument.measure()
    from station.ingest import operator_name, record_from_reading

    return record_from_reading(reading, operator=operator_name(), gloss=gloss)
"""


def test_a_planted_scan_in_a_front_fails_the_check(tmp_path: Path) -> None:
    """A copy of the old viewer scan planted in a temporary tree's ui/models is found, line by line; the
    same front calling station.scan is clean; the allowed writer call is allowed in its one file only."""
    (tmp_path / "ui" / "models").mkdir(parents=True)
    (tmp_path / "ui" / "models" / "planted.py").write_text(_PLANTED_VIEWER_SCAN)
    (tmp_path / "station" / "scan").mkdir(parents=True)
    (tmp_path / "station" / "scan" / "take.py").write_text(_PLANTED_VIEWER_SCAN)  # the scan path may
    found = _scan_copies_under(tmp_path)
    assert [f.split(": ", 1)[0] for f in found] == [
        "ui/models/planted.py:3",  # GLOSS_GEOMETRY_DEG imported
        "ui/models/planted.py:7",  # the gloss meter measured
        "ui/models/planted.py:8",  # the reading sorted
        "ui/models/planted.py:10",  # the colour measured
        "ui/models/planted.py:11",  # record_from_reading imported
        "ui/models/planted.py:13",  # and called
    ], "\n".join(found)
    thin = "from station import scan\n\ndef measure(hub, a):\n    return scan.take(a.driver, device='x')\n"
    assert scan_copies(thin, "station/api/instruments.py") == []
    store = "from station.ingest import store_gloss\n"
    assert scan_copies(store, "station/api/services/qc.py") == []
    assert scan_copies(store, "station/cli/instruments.py") != []
    assert scan_copies("r = self.sink.store_gloss(panel, record)\n", "ui/models/instruments.py") != []


# -- one vocabulary ----------------------------------------------------------------------------------------
# The instrument families are listed in station/drivers/families.py and the ΔE method names, tolerance
# aggregations and booth illuminants in station/model/domain.py; everything else derives from them. A second
# copy — a tuple, list or set (a ``Literal[...]`` too) holding exactly one of these vocabularies, or a message
# spelling one out (``"sim:ma6|ma3|gloss"``, ``"ma6, ma3 or gloss"``) — fails these checks.

VOCABULARIES: dict[str, tuple[str, ...]] = {
    "instrument families (station.drivers.families)": FAMILY_NAMES,
    "ΔE method names (station.model.domain)": DELTA_E_METHOD_NAMES,
    "tolerance aggregations (station.model.domain)": TOLERANCE_AGGREGATIONS,
    "booth illuminants (station.model.domain)": BOOTH_ILLUMINANTS,
    "computed ΔE formulas (station.model.domain)": DELTA_E_COMPUTED,
    "environment-lit ΔE formulas (station.model.domain)": DELTA_E_ENVIRONMENT,
    "ColorSnap metrics (station.model.domain)": SNAP_METRICS,
    "paint types (station.model.domain)": PAINT_TYPES,
}
VOCABULARY_HOMES = ("station/drivers/families.py", "station/model/domain.py")
VOCABULARY_ROOTS = (*ROOTS, "simulators")


def _spelled_out(names: tuple[str, ...]) -> re.Pattern[str]:
    """The names in order, joined by separators (``|``, ``, ``, `` or ``) and an optional ``sim:``-style prefix."""
    joint = r"\s*(?:[|,/]|\bor\b|\band\b)\s*(?:(?:or|and)\s+)?(?:[a-z]+:)?"
    return re.compile(r"(?<![\w-])" + joint.join(re.escape(n) for n in names) + r"(?![\w-])")


_SPELLED = {what: _spelled_out(names) for what, names in VOCABULARIES.items() if len(names) >= 3}


def vocabulary_copies(source: str, where: str = "<source>") -> list[str]:
    """Places in *source* that write out a vocabulary of :data:`VOCABULARIES` instead of importing it."""
    tree = ast.parse(source)
    docs = _docstrings(tree)
    found: list[tuple[int, str]] = []
    for node in ast.walk(tree):
        if isinstance(node, (ast.Tuple, ast.List, ast.Set)) and len(node.elts) >= 2:
            if all(isinstance(e, ast.Constant) and isinstance(e.value, str) for e in node.elts):
                # "sim:ma6" names the family ma6 too
                written = {
                    re.sub(r"^[a-z]+:", "", e.value)
                    for e in node.elts
                    if isinstance(e, ast.Constant) and isinstance(e.value, str)
                }
                for what, names in VOCABULARIES.items():
                    if written == set(names):
                        found.append((node.lineno, f"{where}:{node.lineno}: a copy of the {what}: import it"))
        elif isinstance(node, ast.Constant) and isinstance(node.value, str) and id(node) not in docs:
            spans = {
                what: m.span() for what, pattern in _SPELLED.items() if (m := pattern.search(node.value))
            }
            for what, (a, b) in spans.items():  # a list spelled inside a longer one is that one's copy
                if not any(c <= a and b <= d and (c, d) != (a, b) for c, d in spans.values()):
                    found.append((node.lineno, f"{where}:{node.lineno}: the {what} spelled out: derive it"))
    return [text for _line, text in sorted(found)]


def _vocabulary_copies_under(root: Path) -> list[str]:
    found = []
    for top in VOCABULARY_ROOTS:
        for path in sorted((root / top).rglob("*.py")):
            rel = path.relative_to(root).as_posix()
            if rel in VOCABULARY_HOMES or any(rel.startswith(f) for f in FROZEN):
                continue
            found += vocabulary_copies(path.read_text(), rel)
    return found


def test_the_vocabulary_is_written_once() -> None:
    assert set(FAMILY_NAMES) >= {"ma6", "ma3", "gloss"}
    found = _vocabulary_copies_under(REPO)
    assert found == [], "\n".join(found)


@pytest.mark.parametrize(
    "source",
    [
        'SIM_KINDS = ("ma6", "ma3", "gloss")\n',
        'FAMILIES = ["gloss", "ma6", "ma3"]\n',  # any order
        'Kind = Literal["ma6", "ma3", "gloss"]\n',
        'import re\n_SIM = re.compile(r"^sim:(ma6|ma3|gloss)$")\n',
        'HELP = "sim:ma6 | sim:ma3 | sim:gloss | an address"\n',
        'MSG = "FAMILY@WHERE with FAMILY ma6, ma3 or gloss"\n',
        'METHODS = ("cie76", "cie94", "cie2000", "din6175", "audi2000")\n',
        'DeltaE = Literal["cie76", "cie94", "cie2000", "din6175", "audi2000"]\n',
        'def f(agg: str = "max") -> None:\n    if agg not in {"mean", "max"}:\n        raise ValueError(agg)\n',
        'ILLS = ("D65", "D50", "A", "F2", "F11", "TL84", "LED-B3", "LED-B4")\n',
        'Method = Literal["cie76", "cie94", "cie2000", "din6175"]\n',
        'def f(category: Literal["solid", "metallic", "pearl"] | None = None): ...\n',
        'p.add_argument("--de", choices=("cie76", "cie2000", "din6175"))\n',
        'counts = {t: 0 for t in ("solid", "metallic", "pearl")}\n',
    ],
)
def test_the_vocabulary_check_finds_a_copy(source: str) -> None:
    assert vocabulary_copies(source), source


@pytest.mark.parametrize(
    "source",
    [
        'def f():\n    """Families ma6, ma3 or gloss."""\n',  # docstrings may name them
        'PAIR_DE = Literal["cie76", "din6175"]\n',  # a narrower choice is a different vocabulary
        'DEFAULTS = ("D65", "A", "F11")\n',
        'PAIR = ("ma6", "gloss")\n',
        'AGGREGATE = Literal["mean", "max", "rms", "sum"]\n',
        'LABEL = "ma6x"\n',
    ],
)
def test_the_vocabulary_check_leaves_other_lists_alone(source: str) -> None:
    assert vocabulary_copies(source) == [], source


def test_a_planted_family_list_in_a_temporary_tree_fails_the_check(tmp_path: Path) -> None:
    """The seven copies the family list once had, planted in a temporary tree, are each found; the homes are not."""
    planted = {
        "station/api/settings.py": 'SIM_KINDS = ("ma6", "ma3", "gloss")\n',
        "station/cli/serve.py": 'SIM_CHOICES = ("ma6", "ma3", "gloss")\n',
        "station/drivers/__init__.py": 'FAMILIES = ("ma6", "ma3", "gloss")\n',
        "station/drivers/simproc.py": 'SIM_KINDS = ("ma6", "ma3", "gloss")\n',
        "station/drivers/addresses.py": '_SERIAL_FAMILIES = ("ma6", "ma3", "gloss")\n',
        "simulators/config.py": 'KINDS = ("ma6", "ma3", "gloss")\n',
        "ui/models/devices.py": 'SIM_DEVICES = ("sim:ma6", "sim:ma3", "sim:gloss")\n',
        "station/drivers/families.py": 'NAMES = ("ma6", "ma3", "gloss")\n',  # the home may
        "station/model/domain.py": 'DELTA_E_METHOD_NAMES = ("cie76", "cie94", "cie2000", "din6175", "audi2000")\n',
    }
    for rel, text in planted.items():
        (tmp_path / rel).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / rel).write_text(text)
    found = _vocabulary_copies_under(tmp_path)
    assert sorted(f.split(": ", 1)[0] for f in found) == sorted(
        f"{rel}:1" for rel in planted if rel not in VOCABULARY_HOMES
    ), "\n".join(found)


# -- shared physics written once -----------------------------------------------------------------------------
# A published constant of more than one number lives in station.model; a second literal copy of it (a list or
# tuple of the same numbers, wrapped in np.array or not) anywhere in the product or its benchmarks fails.

PHYSICS_CONSTANTS: dict[str, tuple[float, ...]] = {
    "station.model.colorimetry.REC709_LUMINANCE": tuple(float(v) for v in REC709_LUMINANCE),
}
PHYSICS_HOMES = ("station/model/colorimetry.py",)


def physics_copies(source: str, where: str = "<source>") -> list[str]:
    """Places in *source* that write out a constant of :data:`PHYSICS_CONSTANTS` instead of importing it."""
    found = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, (ast.Tuple, ast.List)) and node.elts:
            values = tuple(_number(e) for e in node.elts)
            for name, constant in PHYSICS_CONSTANTS.items():
                if values == constant:
                    found.append(f"{where}:{node.lineno}: a copy of {name}: import it")
    return found


def test_shared_physics_is_written_once() -> None:
    found = []
    for top in (*VOCABULARY_ROOTS, "bench"):
        for path in sorted((REPO / top).rglob("*.py")):
            rel = path.relative_to(REPO).as_posix()
            if rel not in PHYSICS_HOMES and not any(rel.startswith(f) for f in FROZEN):
                found += physics_copies(path.read_text(), rel)
    assert found == [], "\n".join(found)


@pytest.mark.parametrize(
    "source, copies",
    [
        ("LUMA = np.array([0.2126, 0.7152, 0.0722])\n", 1),
        ("y = rgb @ (0.2126, 0.7152, 0.0722)\n", 1),
        ("w = np.array([0.2126, 0.7152, 0.0722], np.float32)\n", 1),
        ("W = [0.299, 0.587, 0.114]\n", 0),  # Rec. 601 is another constant
        ("W = [0.2126, 0.7152]\n", 0),
    ],
)
def test_the_physics_check_finds_a_copy(source: str, copies: int) -> None:
    assert len(physics_copies(source)) == copies, source
