"""Packaging: every subpackage of mbseig is installed, and the bundled cases are package data.

pyproject.toml lists the packages explicitly (the bundled cases/ folder is mapped to
mbseig.bundled_cases), so a new subpackage must be added there; this test names the one missing.
"""

import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def test_every_subpackage_is_listed_in_pyproject():
    cfg = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]
    listed = set(cfg["packages"])
    found = {".".join(p.parent.relative_to(ROOT).parts)
             for p in (ROOT / "mbseig").rglob("__init__.py")}
    assert found - listed == set()
    assert cfg["package-dir"]["mbseig.bundled_cases"] == "cases"
    assert "mbseig.bundled_cases" in listed


def test_bench_finds_the_bundled_cases():
    from mbseig.bench.cases import case_path

    for name in ("pendulum", "four_bar", "chain_damped", "ziegler_pendulum"):
        assert case_path(name).is_file()
