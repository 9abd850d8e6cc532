"""Text of the report: numbers at fixed precision, user names in every block.

A block is ("h1"|"h2"|"h3"|"p"|"pre", text) | ("table", header, rows) | ("img", path, caption)
| ("gallery", [(path, caption), ...]) (images side by side: the mode animations) |
("toc", entries)."""

from __future__ import annotations

import math

import numpy as np

from ..display import fmt as display_fmt
from ..numerics import user_names

__all__ = ["fmt", "clean"]


def fmt(x, digits=6, bound=None):
    """A value of a table or a sentence: "–" for none or a non-finite value, yes/no for a flag,
    else ``digits`` significant digits under the zero rule (:func:`mbseig.display.fmt`: 0 when
    within ``bound`` of 0)."""
    if x is None:
        return "–"
    if isinstance(x, str):
        return x
    if isinstance(x, (bool, np.bool_)):
        return "yes" if x else "no"
    x = float(x)
    if not math.isfinite(x):
        return "–"
    return display_fmt(x, bound, f".{digits}g")


def clean(blocks):
    out = []
    for b in blocks:
        if b[0] == "table":
            out.append(("table", [user_names(h) for h in b[1]],
                        [[user_names(str(x)) for x in r] for r in b[2]]))
        elif b[0] == "img":
            out.append(("img", b[1], user_names(b[2])))
        elif b[0] == "gallery":
            out.append(("gallery", [(path, user_names(cap)) for path, cap in b[1]]))
        elif b[0] == "toc":
            out.append(b)
        else:
            out.append((b[0], user_names(b[1])))
    return out
