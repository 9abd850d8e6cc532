"""Shared figure machinery: Figures made without pyplot (no global state, the backend never
switched), one style, deterministic PNG output, axis labels and scales."""

from __future__ import annotations

import functools
import math
import re
from pathlib import Path

import numpy as np

from ..errors import CaseError

DPI = 100


STYLE = {"svg.hashsalt": "mbseig", "font.size": 9}
#: the spatial three-view and rotor figures are set one point smaller than the planar ones
SPATIAL_STYLE = {**STYLE, "font.size": 8}


def styled(fn):
    """Draw with mbseig's style in a local rc context (the global rcParams are left alone)."""
    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        import matplotlib

        with matplotlib.rc_context(STYLE):
            return fn(*args, **kwargs)
    return wrapper


def figure(**kw):
    """A Figure without pyplot.  mbseig's figures pass ``layout="constrained"`` (titles,
    labels and legends outside the axes get their room; a figure legend goes at
    ``loc="outside ..."``), so nothing is clipped once :func:`fit` has widened the figure where
    a text is wider than it."""
    from matplotlib.figure import Figure

    return Figure(**kw)


def renderer(fig):
    """The renderer of ``fig`` (an Agg canvas attached when it has none: a Figure made without
    pyplot has only the base canvas)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    if not isinstance(fig.canvas, FigureCanvasAgg):
        FigureCanvasAgg(fig)
    return fig.canvas.get_renderer()


def overflow(fig):
    """How far (inches: left, bottom, right, top, each ≥ 0) the drawn artists of ``fig``
    extend beyond it: all zero when nothing is clipped."""
    r = renderer(fig)
    fig.draw_without_rendering()  # the layout engine places the artists at this size
    bb = fig.get_tightbbox(r)
    w, h = fig.get_size_inches()
    return (max(0.0, -bb.x0), max(0.0, -bb.y0), max(0.0, bb.x1 - w), max(0.0, bb.y1 - h))


def fit(fig, *, pad=0.1, rounds=6):
    """Grow ``fig`` until every artist (titles, suptitle, legends, tick and axis labels) lies
    inside it; returns it.  A figure with a layout engine (constrained) lays itself out again
    at the new size, so the text keeps its size and the axes take the rest."""
    for _ in range(rounds):
        left, bottom, right, top = overflow(fig)
        dx, dy = max(left, right), max(bottom, top)
        if dx <= 1e-3 and dy <= 1e-3:
            break
        w, h = fig.get_size_inches()
        fig.set_size_inches(w + 2 * dx + (pad if dx > 1e-3 else 0.0),
                            h + 2 * dy + (pad if dy > 1e-3 else 0.0), forward=False)
    return fig


def colormap(name):
    import matplotlib

    return matplotlib.colormaps[name]


def save(fig, path, *, dpi=DPI, element="figure"):
    """Write ``fig`` as a PNG (no metadata) to ``path``, grown first so that no text is clipped
    (:func:`fit`); returns the path."""
    path = Path(path)
    fit(fig)
    try:
        fig.savefig(path, dpi=dpi, metadata={"Software": None})
    except OSError as exc:
        raise CaseError(f"cannot write: {exc.strerror or exc}", file=str(path),
                        element=element) from None
    return path


LINESTYLES = ("-", "--", "-.", ":", (0, (5, 1, 1, 1)), (0, (1, 1)))


def decade_scale(ax, which, values):
    """Log (or symlog through 0) scale on ``which`` ("x" or "y") when ``values`` span two
    decades or more; linear otherwise.  Returns the scale name."""
    v = np.asarray([x for x in np.ravel(values) if x is not None and np.isfinite(x)], float)
    pos = np.abs(v[v != 0])
    if pos.size == 0 or pos.max() / pos.min() < 100:
        return "linear"
    setter = ax.set_xscale if which == "x" else ax.set_yscale
    if np.all(v > 0) or np.all(v < 0):
        if np.all(v > 0):
            setter("log")
            return "log"
    setter("symlog", linthresh=float(pos.min()), linscale=0.5)
    return "symlog"


def mode_numbers(res, l):
    """Track → mode number of the sweep's line l (numbered as the mode tables at the line's
    first point: sorted by ω_n, then δ); plain track indices when the result has none."""
    fn = getattr(res, "mode_numbers", None)
    if fn is not None:
        return fn(l)
    return {j: j + 1 for j in range(res.tracks[l].shape[1])}


def axis_label(res, name, prefix=""):
    """``prefix name [unit]`` with the unit from ``res.units`` when known ("1": dimensionless)."""
    unit = (getattr(res, "units", None) or {}).get(name)
    tail = "" if not unit else " [–]" if unit == "1" else f" [{unit}]"
    return f"{prefix}{name}{tail}"


def line_label(res, l):
    line = res.lines[l] if getattr(res, "lines", None) else {}
    units = getattr(res, "units", None) or {}
    return ", ".join(f"{k} = {v:g}" + (f" {units[k]}" if units.get(k) not in (None, "1") else "")
                     for k, v in line.items())


def nice_levels(lo, hi, per_decade=(1, 2, 5)):
    """Round numbers (1, 2, 5 × 10^k) between lo and hi (both > 0)."""
    out = []
    for e in range(int(math.floor(math.log10(lo))) - 1, int(math.ceil(math.log10(hi))) + 1):
        out += [m * 10.0**e for m in per_decade if lo <= m * 10.0**e <= hi]
    return out


def slug(text):
    return re.sub(r"[^A-Za-z0-9_.-]+", "_", text).strip("_") or "case"
