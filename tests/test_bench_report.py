"""Benchmark headers name the machine closely enough to tell two machines of one kind apart: the CPU's model
name, family, model and AVX-512 as /proc/cpuinfo gives them (``bench._report.cpu_model``), read here from
files written by hand in its format."""

from __future__ import annotations

from pathlib import Path

from bench._report import cpu_model

ZEN5 = """processor\t: 0
vendor_id\t: AuthenticAMD
cpu family\t: 26
model\t\t: 2
model name\t: AMD EPYC
flags\t\t: fpu vme sse avx2 avx512f avx512bw

processor\t: 1
vendor_id\t: AuthenticAMD
cpu family\t: 25
model\t\t: 1
model name\t: another CPU
"""

NO_AVX512 = """processor\t: 0
cpu family\t: 6
model\t\t: 106
model name\t: Intel(R) Xeon(R) Platinum 8375C CPU @ 2.90GHz
flags\t\t: fpu sse avx2 avx512_vnni_not_f
"""


def test_family_model_and_avx512_of_the_first_processor(tmp_path: Path) -> None:
    (tmp_path / "cpuinfo").write_text(ZEN5)
    assert cpu_model(str(tmp_path / "cpuinfo")) == "AMD EPYC (family 26, model 2, AVX-512)"


def test_avx512_only_for_the_foundation_flag(tmp_path: Path) -> None:
    (tmp_path / "cpuinfo").write_text(NO_AVX512)
    expected = "Intel(R) Xeon(R) Platinum 8375C CPU @ 2.90GHz (family 6, model 106)"
    assert cpu_model(str(tmp_path / "cpuinfo")) == expected


def test_a_file_without_a_model_name_or_none_at_all_falls_back(tmp_path: Path) -> None:
    (tmp_path / "cpuinfo").write_text("processor\t: 0\nflags\t\t: fpu\n")
    for path in (tmp_path / "cpuinfo", tmp_path / "missing"):
        name = cpu_model(str(path))
        assert name and "family" not in name
