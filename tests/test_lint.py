"""The linter holds on the whole source: ruff with the rules of pyproject.toml ([tool.ruff]:
pycodestyle E and W, pyflakes F, bugbear B, pyupgrade UP, 100 columns) on mbseig/ and tests/
finds nothing.  Run from the suite, so that CI's one test command covers it."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent


def test_ruff_finds_nothing():
    pytest.importorskip("ruff")  # the test extra installs it (pinned in pyproject.toml)
    run = subprocess.run([sys.executable, "-m", "ruff", "check", "--no-cache", "mbseig", "tests"],
                         cwd=ROOT, capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stdout[-4000:] + run.stderr[-2000:]
