"""The bundled cases the benchmark runs on.

``cases/`` of the source tree is installed as the package data ``mbseig.bundled_cases``
(pyproject.toml), so ``mbseig bench`` works from an installed mbseig.  Run from a source
checkout (the package imported from the tree, as the test suite does), the same files are read
from ``cases/`` beside the package.
"""

from __future__ import annotations

from importlib import resources
from pathlib import Path

__all__ = ["case_path"]

_CHECKOUT = Path(__file__).resolve().parents[2] / "cases"


def case_path(name: str) -> Path:
    """Path of the bundled case ``name`` (without ``.toml``)."""
    try:
        return Path(str(resources.files("mbseig.bundled_cases") / f"{name}.toml"))
    except ModuleNotFoundError:  # imported from a source checkout: cases/ beside the package
        return _CHECKOUT / f"{name}.toml"
