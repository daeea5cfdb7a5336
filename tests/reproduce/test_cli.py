"""``station reproduce`` as a user runs it: a subprocess from a temporary folder outside the repository."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]


def station(cwd: Path, *args: str) -> subprocess.CompletedProcess[str]:
    env = dict(os.environ, PYTHONPATH=str(REPO))
    return subprocess.run(
        [sys.executable, "-m", "station.cli", *args],
        capture_output=True,
        text=True,
        timeout=300,
        cwd=cwd,
        env=env,
    )


def test_json_records(tmp_path: Path) -> None:
    """--figure without --out writes nothing; the JSON list carries every field of each quantity."""
    res = station(tmp_path, "reproduce", "--figure", "4.3", "--json")
    assert res.returncode == 0, res.stderr
    rows = json.loads(res.stdout)
    assert len(rows) == 7  # six lights of §4.3.2 and the Fig. 4.3 read-off
    for row in rows:
        assert {
            "figure",
            "quantity",
            "unit",
            "thesis",
            "ours",
            "tolerance",
            "verdict",
            "reason",
        } <= row.keys()
        assert row["verdict"] == "agrees" and row["reason"] is None
        assert abs(row["ours"] - row["thesis"]) <= row["tolerance"]
    assert "reproduce" in res.stderr  # the progress bar
    assert not (tmp_path / "docs").exists()  # --figure without --out writes nothing


def test_markdown_and_png(tmp_path: Path) -> None:
    res = station(tmp_path, "reproduce", "--figure", "3.3", "--out", "site")
    assert res.returncode == 0, res.stderr
    assert "wrote site/thesis.md" in res.stderr
    md = (tmp_path / "site" / "thesis.md").read_text()
    assert "![3.3](thesis/ch3-representations.png)" in md
    assert (tmp_path / "site" / "thesis" / "ch3-representations.png").stat().st_size > 10_000
    assert "**differs**: erratum 5" in md
    assert "→ differs" in res.stdout and "reason: erratum 5" in res.stdout


def test_unknown_figure_exits_2_with_one_line(tmp_path: Path) -> None:
    res = station(tmp_path, "reproduce", "--figure", "9.9")
    assert res.returncode == 2
    lines = [ln for ln in res.stderr.splitlines() if ln.strip()]
    assert len(lines) == 1 and lines[0].startswith("error: figure: expected one of")
