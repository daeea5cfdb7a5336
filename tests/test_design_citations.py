"""Every citation of the design page in code and docs points at a section or erratum that exists.

Code and docs cite ``docs/design.md §N`` (or ``§N.M``) and ``docs/design.md erratum N`` / ``errata N
and M`` / ``errata N–M``; the page declares each target with an HTML anchor (``<a id="s3-1">``,
``<a id="erratum-5">``). The expectation is read from the page itself, independently of the citing file.
"""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DESIGN = ROOT / "docs" / "design.md"
SOURCES = ("station", "db", "ui", "simulators", "tests", "bench", "docs", "scripts")
SUFFIXES = {".py", ".md", ".sh", ".toml"}

CITATION = re.compile(
    r"docs/design\.md(?P<rest>(?:\s*(?:§\s*\d+(?:\.\d+)?|errat(?:um|a)\s+\d+(?:\s*(?:–|-|and|,)\s*\d+)*)"
    r"(?:\s*(?:,|and|;)\s*)?)+)"
)
SECTION = re.compile(r"§\s*(\d+(?:\.\d+)?)")
ERRATA = re.compile(r"errat(?:um|a)\s+(\d+(?:\s*(?:–|-|and|,)\s*\d+)*)")


def _files() -> list[Path]:
    found = [ROOT / "README.md", ROOT / "CONTRIBUTING.md", ROOT / "CHANGELOG.md"]
    for top in SOURCES:
        found += [p for p in (ROOT / top).rglob("*") if p.suffix in SUFFIXES and p.is_file()]
    this = Path(__file__).resolve()
    return [p for p in found if p.exists() and p not in (DESIGN, this)]


def _anchors() -> set[str]:
    return set(re.findall(r'<a id="([^"]+)"></a>', DESIGN.read_text(encoding="utf-8")))


def _errata_numbers(spec: str) -> list[int]:
    numbers = [int(n) for n in re.findall(r"\d+", spec)]
    if re.search(r"\d\s*[–-]\s*\d", spec) and len(numbers) == 2:
        return list(range(numbers[0], numbers[1] + 1))
    return numbers


def _citations() -> list[tuple[str, str]]:
    """(file, anchor) for every citation found."""
    out: list[tuple[str, str]] = []
    for path in _files():
        text = path.read_text(encoding="utf-8", errors="replace")
        for match in CITATION.finditer(text):
            rest = match.group("rest")
            for sec in SECTION.findall(rest):
                out.append((str(path.relative_to(ROOT)), "s" + sec.replace(".", "-")))
            for spec in ERRATA.findall(rest):
                out += [(str(path.relative_to(ROOT)), f"erratum-{n}") for n in _errata_numbers(spec)]
    return out


def test_every_citation_has_a_target() -> None:
    anchors = _anchors()
    cited = _citations()
    assert len(cited) > 20, "the citation scan found almost nothing; is the pattern broken?"
    missing = sorted({(f, a) for f, a in cited if a not in anchors})
    assert missing == [], f"citations of docs/design.md without a target: {missing}"


def test_no_citation_of_a_design_page_outside_the_repository() -> None:
    stale = [
        str(p.relative_to(ROOT))
        for p in _files()
        if re.search(
            r"(?<![\w/])DESIGN\.md|\.\./shared/DESIGN", p.read_text(encoding="utf-8", errors="replace")
        )
    ]
    assert stale == [], f"cite docs/design.md instead of DESIGN.md in {stale}"


def test_anchors_are_numbered_without_gaps() -> None:
    anchors = _anchors()
    sections = sorted(int(a[1:]) for a in anchors if re.fullmatch(r"s\d+", a))
    errata = sorted(int(a.split("-")[1]) for a in anchors if a.startswith("erratum-"))
    assert sections == list(range(1, len(sections) + 1))
    assert errata == list(range(1, len(errata) + 1))
