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
    """How much wider (inches, ≥ 0) ``fig`` must be for its figure-level texts (suptitle,
    figure legends and texts) to fit: the layout engine keeps every axes' own artists (titles,
    labels, tick labels, legends) inside the figure, but it cannot make a figure wider than a
    centred title or legend; measured without laying the figure out (a text's size does not
    depend on where it goes)."""
    r = renderer(fig)
    items = [fig._suptitle, fig._supxlabel, *fig.legends, *fig.texts]
    need = max((a.get_window_extent(r).width for a in items
                if a is not None and a.get_visible()), default=0.0) / fig.dpi
    return max(0.0, need - float(fig.get_size_inches()[0]))


def fit(fig, *, pad=0.2):
    """Widen ``fig`` so that its suptitle and figure legends fit (:func:`overflow`; ``pad``
    inches of margin); returns it.  mbseig's figures use constrained layout, which lays them
    out again at the new size and keeps everything else inside: nothing is clipped."""
    dx = overflow(fig)
    if dx > 0:
        w, h = fig.get_size_inches()
        fig.set_size_inches(w + dx + pad, h, forward=False)
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


def mode_numbers(res, li):
    """Track → mode number of the sweep's line li (numbered as the mode tables at the line's
    first point: sorted by ω_n, then δ); plain track indices when the result has none."""
    fn = getattr(res, "mode_numbers", None)
    if fn is not None:
        return fn(li)
    return {j: j + 1 for j in range(res.tracks[li].shape[1])}


def axis_label(res, name, prefix=""):
    """``prefix name [unit]`` with the unit from ``res.units`` when known ("1": dimensionless)."""
    unit = (getattr(res, "units", None) or {}).get(name)
    tail = "" if not unit else " [–]" if unit == "1" else f" [{unit}]"
    return f"{prefix}{name}{tail}"


def line_label(res, li):
    line = res.lines[li] if getattr(res, "lines", None) else {}
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
