"""``docs/api.md`` generated from the app: every route, the roles that may call it, the codes it answers.

Run ``python -m station.api.docgen`` to rewrite the file, ``python -m station.api.docgen --check`` to
fail (exit 1) when the committed file differs. The hand-written prose lives in ``docs/api.template.md``;
the generator replaces its ``<!-- api:routes -->`` and ``<!-- api:roles -->`` lines.

Where each column comes from:

- **method, path**: every route the app serves (FastAPI's route contexts), those hidden from the
  OpenAPI schema (``/openapi.json``, ``/docs``, ``/redoc``) included.
- **roles**: the scopes the route's ``authorize`` dependencies declare (``Security(authorize,
  scopes=[…])``, anywhere in its dependency tree), mapped through ``station.api.security.ROLE_SCOPES``
  to the roles holding all of them; no ``authorize`` dependency means public (no token).
- **codes**: the non-2xx responses the route declares in the app's OpenAPI schema (401/403 from the
  routers, 404/409/413/503 where declared, 422 wherever FastAPI validates input); a route outside the
  schema that needs a token answers 401.
- **what**: the first sentence of the route's docstring.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from fastapi import FastAPI, routing

from db.models import Role
from station.api.deps import authorize
from station.api.errors import ApiError
from station.api.security import ROLE_SCOPES, Scope

ROOT = Path(__file__).resolve().parents[2]
TEMPLATE = ROOT / "docs" / "api.template.md"
OUTPUT = ROOT / "docs" / "api.md"
ROUTES_MARK = "<!-- api:routes -->"
ROLES_MARK = "<!-- api:roles -->"
PUBLIC = "public (no token)"
_HTTP_METHODS = ("GET", "POST", "PUT", "PATCH", "DELETE")
_SECTIONS_OUTSIDE_SCHEMA = "service"


class DocgenError(ApiError, RuntimeError):
    """The template lacks a marker, or the committed document is out of date (a service-layer error)."""


@dataclass(frozen=True)
class RouteDoc:
    """One method on one path: who may call it and what it can answer."""

    method: str
    path: str
    section: str
    scopes: frozenset[str] | None  # None: public; empty: any authenticated role
    codes: tuple[int, ...]
    what: str

    @property
    def roles(self) -> str:
        """The roles allowed, in the ``Role`` enum's order ("every role" when any token will do)."""
        if self.scopes is None:
            return PUBLIC
        allowed = [r.value for r in Role if all(Scope(s) in ROLE_SCOPES[r] for s in self.scopes)]
        return "every role" if len(allowed) == len(Role) else ", ".join(allowed)


def _authorize_scopes(dependant: Any) -> frozenset[str] | None:
    """Union of the scopes of every ``authorize`` dependency under *dependant*; None if there is none."""
    found: set[str] | None = None
    stack = list(dependant.dependencies)
    while stack:
        dep = stack.pop()
        if dep.call is authorize:
            found = (found or set()) | set(dep.own_oauth_scopes or ()) | set(dep.parent_oauth_scopes or ())
        stack.extend(dep.dependencies)
    return None if found is None else frozenset(found)


_ABBREVIATIONS = ("e.g.", "i.e.", "Fig.", "ch.", "eq.", "vs.")


def _first_sentence(text: str) -> str:
    """The docstring's first sentence: up to the first full stop outside parentheses that is followed
    by a space or the end and is not an abbreviation's."""
    para = " ".join(text.strip().split("\n\n")[0].split())
    depth = 0
    end = len(para)
    for i, ch in enumerate(para):
        depth += (ch == "(") - (ch == ")")
        if ch != "." or depth > 0 or (i + 1 < len(para) and not para[i + 1].isspace()):
            continue
        if not any(para[: i + 1].endswith(a) for a in _ABBREVIATIONS):
            end = i + 1
            break
    return para[:end].replace("|", "\\|")


def collect(app: FastAPI) -> list[RouteDoc]:
    """Every (method, path) the app serves, in the order of the template's sections."""
    schema = app.openapi()
    tag_order = [t["name"] for t in (app.openapi_tags or [])]
    docs: list[RouteDoc] = []
    for context in routing.iter_route_contexts(app.routes):
        route = context.original_route
        if not isinstance(route, routing.APIRoute):
            continue
        scopes = _authorize_scopes(route.dependant)
        for method in sorted(context.methods or (), key=_HTTP_METHODS.index):
            op = schema.get("paths", {}).get(str(context.path_format), {}).get(method.lower())
            if op is not None:
                codes = tuple(sorted(int(c) for c in op.get("responses", {}) if not str(c).startswith("2")))
                section = (op.get("tags") or [_SECTIONS_OUTSIDE_SCHEMA])[0]
                what = _first_sentence(op.get("description") or op.get("summary") or "")
            else:
                codes = () if scopes is None else (401,)
                section = _SECTIONS_OUTSIDE_SCHEMA
                what = _first_sentence(route.endpoint.__doc__ or route.name.replace("_", " "))
            path = str(context.path_format)
            docs.append(RouteDoc(method, path, section, scopes, codes, what))
    order = {name: i for i, name in enumerate([*tag_order, _SECTIONS_OUTSIDE_SCHEMA])}
    return sorted(docs, key=lambda d: order.get(d.section, len(order)))  # stable: route order kept


def routes_markdown(docs: Sequence[RouteDoc]) -> str:
    """The route tables, one per section (OpenAPI tag), with a count line."""
    protected = sum(1 for d in docs if d.scopes is not None)
    lines = [
        f"{len(docs)} routes, {protected} of them behind a bearer token. "
        "Codes are the non-2xx answers each route declares; every route can also answer 413 "
        "(body over the cap).",
        "",
    ]
    sections: list[str] = []
    for d in docs:
        if d.section not in sections:
            sections.append(d.section)
    for section in sections:
        lines += [f"### {section}", "", "| method | path | roles | codes | what |", "|---|---|---|---|---|"]
        for d in docs:
            if d.section == section:
                codes = ", ".join(map(str, d.codes)) or "—"
                lines.append(f"| {d.method} | `{d.path}` | {d.roles} | {codes} | {d.what} |")
        lines.append("")
    return "\n".join(lines).rstrip("\n")


def roles_markdown() -> str:
    """Roles and the scopes each holds (``ROLE_SCOPES``)."""
    rows = [f"| {r.value} | {', '.join(sorted(s.value for s in ROLE_SCOPES[r]))} |" for r in Role]
    return "\n".join(["| role | scopes |", "|---|---|", *rows])


def default_app() -> FastAPI:
    """The service as ``station serve`` builds it (docs behind a token), never started."""
    from station.api import Settings, create_app

    with tempfile.TemporaryDirectory(prefix="cacad-docgen-") as tmp:
        opts: dict[str, Any] = dict(
            data_dir=Path(tmp), simulators=(), load_demo_library=False, public_docs=False
        )
        return create_app(Settings(**opts))


def render(app: FastAPI, template: str) -> str:
    """*template* with its marker lines replaced by the generated tables."""
    for mark in (ROUTES_MARK, ROLES_MARK):
        if template.count(mark) != 1:
            raise DocgenError(f"template must hold the line {mark} exactly once")
    out = template.replace(ROUTES_MARK, routes_markdown(collect(app)))
    out = out.replace(ROLES_MARK, roles_markdown())
    return out if out.endswith("\n") else out + "\n"


def main(argv: Sequence[str] | None = None) -> int:
    """Write (or ``--check``) the API reference; exit 1 when ``--check`` finds it out of date."""
    parser = argparse.ArgumentParser(prog="python -m station.api.docgen", description=__doc__.split("\n")[0])
    parser.add_argument("--check", action="store_true", help="compare instead of writing")
    parser.add_argument("--template", type=Path, default=TEMPLATE)
    parser.add_argument("--output", type=Path, default=OUTPUT)
    args = parser.parse_args(argv)
    text = render(default_app(), args.template.read_text(encoding="utf-8"))
    if args.check:
        current = args.output.read_text(encoding="utf-8") if args.output.is_file() else ""
        if current != text:
            print(f"{args.output.name} is out of date: run python -m station.api.docgen", file=sys.stderr)
            return 1
        return 0
    args.output.write_text(text, encoding="utf-8")
    print(f"wrote {args.output.name}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
