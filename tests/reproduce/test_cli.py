"""``station reproduce`` as a user runs it: a subprocess from a temporary folder outside the repository."""

from __future__ import annotations

import json
import subprocess
from pathlib import Path

from tests.user_cli import run_station


def station(cwd: Path, *args: str) -> subprocess.CompletedProcess[str]:
    return run_station(cwd, *args)


def test_json_records_markdown_and_png(tmp_path: Path) -> None:
    res = station(tmp_path, "reproduce", "--figure", "Fig. 3.3", "--out", "site", "--json")
    assert res.returncode == 0, res.stderr
    rows = json.loads(res.stdout)
    assert len(rows) == 8
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
        if row["verdict"] == "agrees":
            assert row["reason"] is None and abs(row["ours"] - row["thesis"]) <= row["tolerance"]
        else:
            assert (
                row["reason"].startswith("erratum 5") and abs(row["ours"] - row["thesis"]) > row["tolerance"]
            )
    assert [r["verdict"] for r in rows].count("differs") == 1
    assert "reproduce" in res.stderr and "wrote site/thesis.md" in res.stderr  # progress, then the file
    md = (tmp_path / "site" / "thesis.md").read_text()
    assert "![3.3](thesis/ch3-representations.png)" in md
    assert (tmp_path / "site" / "thesis" / "ch3-representations.png").stat().st_size > 10_000
    assert "**differs**: erratum 5" in md
    assert not (tmp_path / "docs").exists()  # only --out is written


def test_unknown_figure_exits_2_with_one_line(tmp_path: Path) -> None:
    res = station(tmp_path, "reproduce", "--figure", "9.9")
    assert res.returncode == 2
    lines = [ln for ln in res.stderr.splitlines() if ln.strip()]
    assert len(lines) == 1 and lines[0].startswith("error: figure: expected one of")
    assert not any(tmp_path.iterdir())  # nothing written
