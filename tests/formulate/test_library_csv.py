"""Library CSV round trip, strict validation (row/column named), hierarchy and filters."""

from __future__ import annotations

import io

import numpy as np
import pytest

from station.formulate.errors import LibraryFormatError
from station.formulate.library import Library, LibraryFilter, classify, hierarchy_counts
from station.formulate.library_csv import read_library_csv, write_library_csv

HEADER = "code,type,gloss_gu,L15,a15,b15,L45,a45,b45,L110,a110,b110"


def _read(text: str) -> Library:
    return read_library_csv(io.StringIO(text))


def test_round_trip_is_lossless_to_four_decimals(small_library: Library, tmp_path) -> None:
    path = tmp_path / "lib.csv"
    write_library_csv(small_library, path)
    back = read_library_csv(path)
    assert back.codes.tolist() == small_library.codes.tolist()
    assert back.types.tolist() == small_library.types.tolist()
    assert back.angles_deg[:3] == (15.0, 45.0, 110.0)
    assert set(back.angles_deg) == set(small_library.angles_deg)
    for a in small_library.angles_deg:
        got = back.angle_columns((a,))
        want = small_library.angle_columns((a,))
        assert np.max(np.abs(got - want)) <= 0.5e-4 + 1e-12
    assert np.max(np.abs(back.gloss_gu - small_library.gloss_gu)) <= 0.5e-4 + 1e-12
    again = tmp_path / "again.csv"
    write_library_csv(back, again)
    assert again.read_bytes() == path.read_bytes()


def test_extra_angle_triples_are_read() -> None:
    lib = _read(HEADER + ",L25,a25,b25,L-15,a-15,b-15\nX1,metallic,80,90,1,2,60,1,2,30,1,2,80,1,2,95,1,2\n")
    assert lib.angles_deg == (15.0, 45.0, 110.0, 25.0, -15.0)
    assert lib.paint(0).lab_at(-15) == (95.0, 1.0, 2.0)


@pytest.mark.parametrize(
    ("text", "row", "column"),
    [
        (HEADER + "\nA,solid,50,101,0,0,50,0,0,50,0,0\n", None, None),  # L 101 is accepted (<= 150)
        (HEADER + "\nA,solid,50,201,0,0,50,0,0,50,0,0\n", 2, "L15"),
        (HEADER + "\nA,solid,50,50,0,0,50,0,0,50,0,0\nB,paint,50,50,0,0,50,0,0,50,0,0\n", 3, "type"),
        (HEADER + "\nA,solid,-1,50,0,0,50,0,0,50,0,0\n", 2, "gloss_gu"),
        (HEADER + "\nA,solid,50,50,0,0,50,x,0,50,0,0\n", 2, "a45"),
        (HEADER + "\nA,solid,50,50,0,0,50,0,nan,50,0,0\n", 2, "b45"),
        (HEADER + "\nA,solid,50,50,0,0,50,0,0,50,0,0\nA,solid,50,50,0,0,50,0,0,50,0,0\n", 3, "code"),
        (HEADER + "\nA,solid,50,50,0,0,50,0,0,50,0\n", 2, None),
        (HEADER + "\n,solid,50,50,0,0,50,0,0,50,0,0\n", 2, "code"),
        # a bare carriage return inside an unquoted field is malformed CSV, not a crash
        (HEADER + "\nA,solid,50,50,0,0,50,0,0,50,0,0\nB\rC,solid,50,50,0,0,50,0,0,50,0,0\n", 3, None),
    ],
)
def test_validation_names_row_and_column(text: str, row: int | None, column: str | None) -> None:
    if row is None:
        assert len(_read(text)) == 1
        return
    with pytest.raises(LibraryFormatError) as err:
        _read(text)
    assert err.value.row == row
    assert err.value.column == column
    assert f"row {row}" in str(err.value)


@pytest.mark.parametrize(
    "text",
    [
        "",
        "code,type,gloss\n",
        "code,type,gloss_gu,L15,a15\n",
        "code,type,gloss_gu,L45,a45,b45,L15,a15,b15,L110,a110,b110\n",
        "code,type,gloss_gu,L15,a15,b15,L45,a45,b45,L110,b110,a110\n",
        "code,type,gloss_gu,L15,a15,b15,L45,a45,b45,L110,a110,b111\n",
        HEADER + "\n",
    ],
)
def test_bad_headers_and_empty_files_are_refused(text: str) -> None:
    with pytest.raises(LibraryFormatError):
        _read(text)


def test_missing_file_is_a_typed_error(tmp_path) -> None:
    with pytest.raises(LibraryFormatError):
        read_library_csv(tmp_path / "absent.csv")


def test_hierarchy_groups_follow_hue_and_value() -> None:
    lab45 = np.array(
        [
            [50, 40, 0],
            [50, 0, 40],
            [50, -40, 0],
            [50, 0, -40],
            [80, 1, 1],
            [50, 0, 0],
            [20, 0, 0],
            [50, 30, -30],
        ]
    )
    types = np.array(["solid", "metallic", "pearl", "solid", "solid", "metallic", "pearl", "solid"])
    top, kind, group = classify(types, lab45)
    assert top.tolist() == [
        "solids",
        "metallics+pearls",
        "metallics+pearls",
        "solids",
        "solids",
        "metallics+pearls",
        "metallics+pearls",
        "solids",
    ]
    assert kind.tolist() == ["chromatic"] * 4 + ["neutral"] * 3 + ["chromatic"]
    assert group.tolist() == [
        "red",
        "yellow",
        "green",
        "blue",
        "light",
        "medium",
        "dark",
        "red",
    ]  # 315° is red


def test_hierarchy_counts_cover_every_paint(small_library: Library) -> None:
    counts = hierarchy_counts(small_library)
    total = sum(v for s in counts.values() for kinds in s.values() for v in kinds.values())
    assert total == len(small_library)
    solids = sum(counts["solids"][k][g] for k in counts["solids"] for g in counts["solids"][k])
    assert solids == int(np.sum(small_library.types == "solid"))


def test_filters_match_closed_form_indices(small_library: Library) -> None:
    std = small_library.angle_columns()
    l15, l45, l110 = std[:, 0, 0], std[:, 1, 0], std[:, 2, 0]
    with np.errstate(invalid="ignore"):
        flop = 2.69 * (l15 - l110) ** 1.11 / l45**0.86  # eq 5.3.1, independent of the model's code
    chroma = np.abs(np.hypot(std[:, 0, 1], std[:, 0, 2]) - np.hypot(std[:, 2, 1], std[:, 2, 2]))  # eq 5.3.2
    f = LibraryFilter(types=frozenset({"metallic", "pearl"}), flop=(5.0, 15.0))
    mask = f.mask(small_library)
    idx = small_library.indices()
    defined = np.isfinite(idx["flop"])
    assert np.allclose(idx["flop"][defined], flop[defined], rtol=1e-9)
    want = np.isin(small_library.types, ["metallic", "pearl"]) & defined & (flop >= 5) & (flop <= 15)
    assert mask.tolist() == want.tolist()
    assert mask.sum() > 5
    g = LibraryFilter(chroma=(None, 2.0))
    assert g.mask(small_library).tolist() == (chroma <= 2.0).tolist()
    assert LibraryFilter(types=frozenset({"solid"})).apply(small_library).types.tolist() == ["solid"] * 120


@pytest.mark.parametrize(
    "kwargs", [{"types": frozenset({"matte"})}, {"flop": (5.0, 1.0)}, {"hue_shift": (float("nan"), None)}]
)
def test_bad_filters_are_refused(kwargs: dict) -> None:
    with pytest.raises(ValueError):
        LibraryFilter(**kwargs)
