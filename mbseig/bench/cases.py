"""The bundled cases the benchmark runs on, and the machine's load it runs under.

``cases/`` of the source tree is installed as the package data ``mbseig.bundled_cases``
(pyproject.toml), so ``mbseig bench`` works from an installed mbseig.  Run from a source
checkout (the package imported from the tree, as the test suite does), the same files are read
from ``cases/`` beside the package.
"""

from __future__ import annotations

import os
from importlib import resources
from pathlib import Path

__all__ = ["case_path", "load_average"]

_CHECKOUT = Path(__file__).resolve().parents[2] / "cases"


def case_path(name: str) -> Path:
    """Path of the bundled case ``name`` (without ``.toml``)."""
    try:
        return Path(str(resources.files("mbseig.bundled_cases") / f"{name}.toml"))
    except ModuleNotFoundError:  # imported from a source checkout: cases/ beside the package
        return _CHECKOUT / f"{name}.toml"


def load_average():
    """The machine's load averages over 1, 5 and 15 minutes (None where the system has none)."""
    try:
        return [round(x, 2) for x in os.getloadavg()]
    except (AttributeError, OSError):
        return None
