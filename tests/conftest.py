import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
CASES = ROOT / "cases"
sys.path.insert(0, str(Path(__file__).resolve().parent))


@pytest.fixture
def cases_dir():
    return CASES


def write_case(tmp_path, text, name="case.toml"):
    """Write a case file for a test and return its path."""
    p = tmp_path / name
    p.write_text(text)
    return p
