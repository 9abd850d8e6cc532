"""Figures of spatial models: mode shapes in three orthographic views and Campbell diagrams.

Like :mod:`mbseig.plots`, every function returns a :class:`matplotlib.figure.Figure` built
without pyplot (no backend switch, no global state) and drawn in a local rc context;
:func:`mbseig.plots.save` writes it.  Nothing here imports a stage: the model and results are
read by their attributes (duck typing):

- ``model.points``: name → affine map (callable on q, ``.idx`` empty for a fixed point);
- ``model.bodies``: name → record whose ``markers`` are names in ``model.points`` (for a
  spatial body: its centre of mass and every point where a joint, spring or bushing acts), or
  whose ``points`` are two such names (planar bodies);
- a Campbell result: ``values``, ``parameter``, ``speeds``, ``harmonic``, ``frequency``,
  ``log_decrement``, ``whirl`` (per point, per track) and ``critical_speeds``.

A body is drawn rigid: the displaced configuration q₀ ± a·L·Re(e^{−iφ} x) is projected back
onto the constraints Φ(q) = 0 (:func:`mbseig.plots.project_constraints`), and its markers are
affine maps of the body's frame, so they move together; each body is drawn as the segments
from its centre of mass to its other markers.
"""

from __future__ import annotations

import math

import numpy as np

from .common import STYLE, figure, save
from .mechanism import project_constraints

#: the three-view and Campbell figures are set one point smaller than the planar ones
SPATIAL_STYLE = {**STYLE, "font.size": 8}

__all__ = ["VIEWS", "WHIRL_COLOURS", "campbell_diagram", "save", "spatial_modes"]

#: (horizontal axis, vertical axis, title) of the three orthographic views
VIEWS = ((0, 1, "top (x, y)"), (0, 2, "front (x, z)"), (1, 2, "side (y, z)"))
WHIRL_COLOURS = {"forward": "tab:blue", "backward": "tab:red", "mixed": "tab:gray",
                 "none": "tab:green", None: "k"}



def _body_polylines(model, q):
    """Per body: an array (k, 3) of its markers, the first one the centre of mass."""
    out = []
    for b in model.bodies.values():
        names = b.get("markers") or list(b.get("points", ()))
        pts = [np.asarray(model.points[nm](q), float) for nm in names]
        pts = [np.pad(p, (0, 3 - p.size)) for p in pts]
        if pts:
            out.append(np.array(pts))
    return out


def _real_shape(v):
    v = np.asarray(v)
    j = int(np.argmax(np.abs(v)))
    vr = (v * np.exp(-1j * np.angle(v[j]))).real if np.iscomplexobj(v) else v
    return vr / max(np.max(np.abs(vr)), 1e-300)


def _draw(ax, model, q, h, v, **kw):
    for P in _body_polylines(model, q):
        for k in range(1, len(P)):
            ax.plot(P[[0, k], h], P[[0, k], v], "-", **kw)
        ax.plot(P[:1, h], P[:1, v], "o", ms=3, **kw)


def spatial_modes(model, q0, shapes, labels, *, amplitude=0.15, title=""):
    """One row a mode, three orthographic views a row: the model at equilibrium (black) and
    displaced by ± the mode shape (red/blue), bodies drawn rigid (module docstring)."""
    import matplotlib

    with matplotlib.rc_context(SPATIAL_STYLE):
        n = max(len(labels), 1)
        fig = figure(figsize=(10.5, 3.2 * n))
        axes = fig.subplots(n, 3, squeeze=False)
        L = float(getattr(model, "length_scale", 1.0))
        fixed = [np.pad(np.asarray(a(q0), float), (0, 3 - a.dim)) for nm, a in model.points.items()
                 if a.idx.size == 0]
        for k in range(len(labels)):
            d = amplitude * L * _real_shape(shapes[:, k])
            # moved along the mode and projected back onto Φ(q) = 0: unit vectors stay unit
            # and rigid bodies rigid (a linear displacement stretches them by O(a²))
            q_plus = project_constraints(model, q0 + d)[0]
            q_minus = project_constraints(model, q0 - d)[0]
            for c, (h, v, name) in enumerate(VIEWS):
                ax = axes[k][c]
                _draw(ax, model, q0, h, v, color="k", lw=2)
                _draw(ax, model, q_plus, h, v, color="tab:red", lw=1, alpha=0.8)
                _draw(ax, model, q_minus, h, v, color="tab:blue", lw=1, alpha=0.8)
                for p in fixed:
                    ax.plot(p[h], p[v], "ks", ms=4)
                _min_span(ax, 0.2 * L)
                ax.set_aspect("equal", adjustable="datalim")
                ax.set_xlabel("xyz"[h] + " [m]")
                ax.set_ylabel("xyz"[v] + " [m]")
                ax.set_title(f"{labels[k]} — {name}" if c == 0 else name, fontsize=8)
                ax.grid(True, lw=0.3)
        if title:
            fig.suptitle(title)
        fig.tight_layout(rect=(0, 0, 1, 0.985 if title else 1))
        return fig


def _min_span(ax, span):
    """Axis limits at least ``span`` wide (a view along a body's line is not blown up to
    show rounding residues)."""
    for get, set_ in ((ax.get_xlim, ax.set_xlim), (ax.get_ylim, ax.set_ylim)):
        lo, hi = get()
        if hi - lo < span:
            mid = 0.5 * (lo + hi)
            set_(mid - span / 2, mid + span / 2)


def campbell_diagram(res):
    """Frequency against the swept parameter, coloured by whirl, with the excitation line
    h·|Ω| (dashed) and the critical speeds (circles); below, the logarithmic decrement."""
    import matplotlib
    from matplotlib.lines import Line2D

    with matplotlib.rc_context(SPATIAL_STYLE):
        fig = figure(figsize=(8.8, 7))
        a1, a2 = fig.subplots(2, 1, sharex=True, gridspec_kw={"height_ratios": [3, 1.3]})
        x = np.asarray(res.values, float)
        F = np.asarray(res.frequency) / (2 * math.pi)
        LD = np.asarray(res.log_decrement)
        for j in range(F.shape[1]):
            for k in range(len(x) - 1):
                colour = WHIRL_COLOURS.get(res.whirl[k][j], "k")
                a1.plot(x[k:k + 2], F[k:k + 2, j], "-", color=colour, lw=1.5)
                a2.plot(x[k:k + 2], LD[k:k + 2, j], "-", color=colour, lw=1.2)
        a1.plot(x, res.harmonic * np.abs(res.speeds) / (2 * math.pi), "k--", lw=1)
        for c in res.critical_speeds:
            a1.plot(c["value"], c["frequency"] / (2 * math.pi), "o", mfc="none",
                    color=WHIRL_COLOURS.get(c["whirl"], "k"), ms=7)
        handles = [Line2D([], [], color=WHIRL_COLOURS[w], label=w) for w in
                   ("forward", "backward", "mixed", "none")]
        handles.append(Line2D([], [], color="k", ls="--", label=f"{res.harmonic:g}x excitation"))
        a1.legend(handles=handles, fontsize=7, loc="upper left", bbox_to_anchor=(1.02, 1.0),
                  borderaxespad=0.0)  # outside the axes, never over the curves
        a1.set_ylabel("frequency [Hz]")
        a1.set_title(f"Campbell diagram of {res.case}: circles = critical speeds")
        a2.set_ylabel("log decrement")
        a2.set_xlabel(res.parameter)
        a1.grid(True, lw=0.3)
        a2.grid(True, lw=0.3)
        fig.tight_layout()
        return fig
