"""What a reader needs to know which inputs made a report: versions, date and the case's hash."""

from __future__ import annotations

import hashlib
import os
import time
from pathlib import Path

__all__ = ["provenance"]


def provenance(case) -> dict:
    """mbseig version, date (UTC; ``SOURCE_DATE_EPOCH`` when set, for reproducible builds) and
    the SHA-256 of the case file: what a reader needs to know which inputs made the report."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        ver = version("mbseig")
    except PackageNotFoundError:  # not installed as a distribution (a source tree)
        ver = "unknown"
    epoch = os.environ.get("SOURCE_DATE_EPOCH")
    try:
        stamp = float(epoch) if epoch else time.time()
    except ValueError:
        stamp = time.time()
    date = time.strftime("%Y-%m-%d", time.gmtime(stamp))
    try:
        digest = hashlib.sha256(Path(case.source).read_bytes()).hexdigest()
    except (OSError, TypeError):
        digest = "unavailable"
    import numpy
    import scipy

    return {"mbseig": ver, "date": date, "case": Path(str(case.source)).name,
            "sha256": digest, "numpy": numpy.__version__, "scipy": scipy.__version__}
