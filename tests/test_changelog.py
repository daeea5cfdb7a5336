"""CHANGELOG.md keeps the Keep a Changelog form: under each version, each kind of change has one heading,
in the order Added, Changed, Deprecated, Removed, Fixed, Security, and nothing else."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

CHANGELOG = Path(__file__).resolve().parents[1] / "CHANGELOG.md"
KINDS = ("Added", "Changed", "Deprecated", "Removed", "Fixed", "Security")


def headings(text: str) -> dict[str, list[str]]:
    """``{version heading: [kind headings in order]}`` of a changelog's text."""
    out: dict[str, list[str]] = {}
    version = None
    for line in text.splitlines():
        if line.startswith("## "):
            version = line[3:].strip()
            out[version] = []
        elif line.startswith("### ") and version is not None:
            out[version].append(line[4:].strip())
    return out


def problems(text: str) -> list[str]:
    """Every way *text* departs from the form (empty when it keeps it)."""
    found = []
    for version, kinds in headings(text).items():
        if not re.fullmatch(r"\[Unreleased\]|\[\d+\.\d+\.\d+\] - \d{4}-\d{2}-\d{2}", version):
            found.append(f"{version}: not '[Unreleased]' or '[X.Y.Z] - YYYY-MM-DD'")
        unknown = [k for k in kinds if k not in KINDS]
        if unknown:
            found.append(f"{version}: unknown headings {unknown}")
        known = [k for k in kinds if k in KINDS]
        if len(set(known)) != len(known):
            found.append(f"{version}: a heading repeats: {known}")
        elif known != sorted(known, key=KINDS.index):
            found.append(f"{version}: headings out of order: {known}")
    return found


def test_the_changelog_keeps_the_form() -> None:
    assert problems(CHANGELOG.read_text()) == []


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("## [Unreleased]\n### Fixed\n- a\n### Added\n- b\n", "out of order"),
        ("## [Unreleased]\n### Fixed\n- a\n### Fixed\n- b\n", "repeats"),
        ("## [Unreleased]\n### Improvements\n- a\n", "unknown"),
        ("## 0.2.0\n### Added\n- a\n", "not '[Unreleased]'"),
    ],
)
def test_the_check_finds_each_departure(text: str, message: str) -> None:
    assert any(message in p for p in problems(text))
