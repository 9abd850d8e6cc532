"""Figures: sweeps, pole maps, mechanism mode shapes, time-domain checks (the drawing layer).

Every function returns a :class:`matplotlib.figure.Figure` built without pyplot, so no global
state changes: the backend a notebook or application chose stays as it is, and no figure is kept
alive by a figure manager.  :func:`save` writes one as a PNG without metadata, so the output is
byte-identical for identical inputs.  matplotlib is imported here only, when a figure is asked
for.  The functions take result objects by their attributes (duck typing) and import no stage.
"""

from __future__ import annotations

import functools
import math
import re
from pathlib import Path

import numpy as np

from .errors import CaseError
from .numerics import element_name

__all__ = ["root_locus", "modes_vs_parameter", "stability_map", "bifurcation_diagram",
           "stability_chart", "pole_map", "mechanism_modes", "plot_check", "speed_accuracy", "save"]

DPI = 100
_STYLE = {"svg.hashsalt": "mbseig", "font.size": 9}


def _styled(fn):
    """Draw with mbseig's style in a local rc context (the global rcParams are left alone)."""
    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        import matplotlib

        with matplotlib.rc_context(_STYLE):
            return fn(*args, **kwargs)
    return wrapper


def _figure(**kw):
    from matplotlib.figure import Figure

    return Figure(**kw)


def _cmap(name):
    import matplotlib

    return matplotlib.colormaps[name]


def save(fig, path, *, dpi=DPI, element="figure"):
    """Write ``fig`` as a PNG (no metadata) to ``path``; returns the path."""
    path = Path(path)
    try:
        fig.savefig(path, dpi=dpi, metadata={"Software": None})
    except OSError as exc:
        raise CaseError(f"cannot write: {exc.strerror or exc}", file=str(path),
                        element=element) from None
    return path


_LINESTYLES = ("-", "--", "-.", ":", (0, (5, 1, 1, 1)), (0, (1, 1)))


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


def _mode_numbers(res, l):
    """Track → mode number of the sweep's line l (numbered as the mode tables at the line's
    first point: sorted by ω_n, then δ); plain track indices when the result has none."""
    fn = getattr(res, "mode_numbers", None)
    if fn is not None:
        return fn(l)
    return {j: j + 1 for j in range(res.tracks[l].shape[1])}


def _axis_label(res, name, prefix=""):
    """``prefix name [unit]`` with the unit from ``res.units`` when known ("1": dimensionless)."""
    unit = (getattr(res, "units", None) or {}).get(name)
    tail = "" if not unit else " [–]" if unit == "1" else f" [{unit}]"
    return f"{prefix}{name}{tail}"


def _line_label(res, l):
    line = res.lines[l] if getattr(res, "lines", None) else {}
    units = getattr(res, "units", None) or {}
    return ", ".join(f"{k} = {v:g}" + (f" {units[k]}" if units.get(k) not in (None, "1") else "")
                     for k, v in line.items())


@_styled
def root_locus(res):
    """Tracked eigenvalues in the s-plane along the first axis: one colour a mode (numbered as
    the mode tables at the first point), one line style a line of the other axes; both halves
    of a pair drawn in the same colour; dot = first value; x = located boundary.  Legend outside
    the axes."""
    from matplotlib.lines import Line2D

    fig = _figure(figsize=(8.5, 5))
    ax = fig.subplots()
    cmap = _cmap("tab10")
    modes_seen = {}
    for l, S in enumerate(res.tracks):
        numbers = _mode_numbers(res, l)
        ls = _LINESTYLES[l % len(_LINESTYLES)]
        for j in res.listed_tracks(S):
            col = S[:, j]
            ok = ~np.isnan(col)
            if not ok.any():
                continue
            m = numbers.get(j, j + 1)
            c = cmap((m - 1) % 10)
            modes_seen.setdefault(m, c)
            for sign in ((1, -1) if np.any(col.imag[ok] != 0) else (1,)):
                ax.plot(col.real[ok], sign * col.imag[ok], linestyle=ls, color=c, lw=1.1,
                        alpha=0.85)
            first = np.flatnonzero(ok)[0]
            ax.plot(col.real[first], col.imag[first], "o", color=c, ms=3.5)
    for b in res.boundaries:
        ax.plot(b["eigenvalue"][0], b["eigenvalue"][1], "kx", ms=8, mew=1.5)
        ax.plot(b["eigenvalue"][0], -b["eigenvalue"][1], "kx", ms=8, mew=1.5)
    ax.axvline(0.0, color="k", lw=0.8)
    ax.set_xlabel("Re s = −δ [1/s]")
    ax.set_ylabel("Im s = ±ω_d [rad/s]")
    title = f"root locus of {Path(res.case).stem}" + (f" ({res.config})" if res.config else "")
    ax.set_title(f"{title}: {res.axis} from {res.values[0]:g} to {res.values[-1]:g}")
    ax.grid(True, lw=0.3)
    handles = [Line2D([], [], color=c, lw=1.5, label=f"mode {m}") for m, c in sorted(modes_seen.items())]
    if len(res.tracks) > 1:
        handles += [Line2D([], [], color="0.3", linestyle=_LINESTYLES[l % len(_LINESTYLES)],
                           label=_line_label(res, l)) for l in range(len(res.tracks))]
    handles += [Line2D([], [], ls="none", marker="o", color="0.3", ms=3.5,
                       label=f"{res.axis} = {res.values[0]:g}"),
                Line2D([], [], ls="none", marker="x", color="k", ms=7, label="stability boundary")]
    ax.legend(handles=handles, fontsize=7, loc="upper left", bbox_to_anchor=(1.02, 1.0),
              borderaxespad=0.0, title=f"modes numbered at {res.axis} = {res.values[0]:g}",
              title_fontsize=7)
    fig.tight_layout()
    return fig


@_styled
def modes_vs_parameter(res):
    """Damped frequency ω_d/2π and damping δ of each mode against the first axis (one colour a
    mode numbered as the mode tables at the first point, one line style a line of the other
    axes); legend outside the axes; log scales where the values span decades."""
    from matplotlib.lines import Line2D

    fig = _figure(figsize=(8.5, 6))
    a1, a2 = fig.subplots(2, 1, sharex=True)
    cmap = _cmap("tab10")
    x = np.asarray(res.values, float)
    modes_seen = {}
    for l, S in enumerate(res.tracks):
        numbers = _mode_numbers(res, l)
        ls = _LINESTYLES[l % len(_LINESTYLES)]
        for j in res.listed_tracks(S):
            col = S[:, j]
            m = numbers.get(j, j + 1)
            c = cmap((m - 1) % 10)
            modes_seen.setdefault(m, c)
            a1.plot(x, np.abs(col.imag) / (2 * math.pi), linestyle=ls, color=c, lw=1.1)
            a2.plot(x, -col.real, linestyle=ls, color=c, lw=1.1)
    for b in res.boundaries:
        a2.axvline(b["value"], color="r", lw=0.8, ls="--")
    a2.axhline(0.0, color="k", lw=0.8)
    a1.set_ylabel("damped frequency ω_d/2π [Hz]")
    a2.set_ylabel("damping δ = −Re s [1/s]")
    a2.set_xlabel(_axis_label(res, res.axis))
    a2.set_yscale("symlog", linthresh=1.0)
    decade_scale(a2, "x", x)
    a1.grid(True, lw=0.3)
    a2.grid(True, lw=0.3)
    a1.set_title("modes tracked by MAC; red dashed: stability boundaries")
    handles = [Line2D([], [], color=c, lw=1.5, label=f"mode {m}") for m, c in sorted(modes_seen.items())]
    if len(res.tracks) > 1:
        handles += [Line2D([], [], color="0.3", linestyle=_LINESTYLES[l % len(_LINESTYLES)],
                           label=_line_label(res, l)) for l in range(len(res.tracks))]
    handles.append(Line2D([], [], color="r", ls="--", lw=0.8, label="stability boundary"))
    a1.legend(handles=handles, fontsize=7, loc="upper left", bbox_to_anchor=(1.02, 1.0),
              borderaxespad=0.0, title=f"modes numbered at {res.axis} = {res.values[0]:g}",
              title_fontsize=7)
    fig.tight_layout()
    return fig


@_styled
def stability_map(res):
    """Two-parameter map: spectral abscissa max Re s (colour), the α = 0 contour and the located
    boundaries (points)."""
    fig = _figure(figsize=(7.5, 5.4))
    ax = fig.subplots()
    x, y = res.axes[0][1], res.axes[1][1]
    A = res.abscissa_grid()  # (len(x), len(y))
    finite = np.abs(A[np.isfinite(A)])  # every point failed: an empty map, not a crash
    lim = (float(finite.max()) if finite.size else 0.0) or 1.0
    from matplotlib.colors import SymLogNorm

    thresh = max(lim * 1e-3, 1e-12)
    mesh = ax.pcolormesh(x, y, A.T, shading="nearest", cmap="RdBu_r",
                         norm=SymLogNorm(linthresh=thresh, vmin=-lim, vmax=lim))
    # ticks: 0 and ±10^k down to ten times the linear threshold (no crowding around 0)
    decades = [10.0**k for k in range(math.ceil(math.log10(10 * thresh)),
                                       math.floor(math.log10(lim)) + 1)][::-1]
    step = max(1, math.ceil(len(decades) / 3))
    ticks = [-d for d in decades[::step]] + [0.0] + [d for d in decades[::step]][::-1]
    fig.colorbar(mesh, ax=ax, ticks=ticks,
                 label="spectral abscissa max Re s [1/s] (red: unstable)")
    if A.shape[0] > 1 and A.shape[1] > 1 and np.nanmin(A) < 0 < np.nanmax(A):
        ax.contour(x, y, A.T, levels=[0.0], colors="k", linewidths=1)
    from matplotlib.lines import Line2D

    for b in res.boundaries:
        ax.plot(b["value"], b["fixed"][res.axes[1][0]], "ko", ms=4)
    for c in getattr(res, "curves", []) or []:
        pts = [p for p in c["points"] if p["value"] is not None]
        ax.plot([p["value"] for p in pts], [p["p2"] for p in pts], "-", color="tab:green", lw=1.5)
    decade_scale(ax, "x", x)
    decade_scale(ax, "y", y)
    ax.set_xlabel(_axis_label(res, res.axes[0][0]))
    ax.set_ylabel(_axis_label(res, res.axes[1][0]))
    ax.set_title("stability map (spectral abscissa on the grid)")
    handles = [Line2D([], [], color="k", lw=1, label="α = max Re s = 0 (grid contour)"),
               Line2D([], [], color="k", ls="none", marker="o", ms=4,
                      label="boundary located by root finding")]
    if getattr(res, "curves", None):
        handles.append(Line2D([], [], color="tab:green", lw=1.5, label="boundary followed across "
                              + res.axes[1][0]))
    fig.legend(handles=handles, loc="lower center", ncol=len(handles), fontsize=7, frameon=False)
    fig.tight_layout(rect=(0, 0.06, 1, 1))
    return fig


_STAB_STYLE = {"stable": ("tab:blue", "-"), "critical": ("tab:orange", "-"),
               "unstable": ("tab:red", "--")}


@_styled
def bifurcation_diagram(res):
    """The followed branches: the swept parameter against the diagram variable (a named angle or
    a coordinate), solid where stable (blue) or critical (orange), dashed red where unstable;
    folds (triangles), branch points (squares) and jumps (dotted) marked."""
    fig = _figure(figsize=(8.5, 5))
    ax = fig.subplots()
    var = res.diagram.get("variable", "")
    seen = set()
    n_lines = len(res.branches)
    for l, branch in enumerate(res.branches):
        # lines that share a branch (parameters that do not enter the statics) would hide each
        # other: the first line is drawn widest, each next one narrower on top of it
        lw = 1.4 + 1.6 * (n_lines - 1 - l)
        pts = [b for b in branch if b.get("value") is not None]
        for a, b in zip(pts, pts[1:]):
            if a["segment"] != b["segment"]:
                ax.plot([a["p"], b["p"]], [a["value"], b["value"]], ":", color="0.6", lw=0.8)
                continue
            st = (b.get("verdict") or b.get("static") or "stable")
            st = st if st in _STAB_STYLE else "critical"
            color, ls = _STAB_STYLE[st]
            label = None if st in seen else st
            seen.add(st)
            ax.plot([a["p"], b["p"]], [a["value"], b["value"]], ls, color=color, lw=lw,
                    label=label, alpha=0.85 if n_lines > 1 else 1.0)
        for b in pts:
            if b["kind"] == "fold":
                ax.plot(b["p"], b["value"], "k^", ms=7, label=None if "fold" in seen else "fold")
                seen.add("fold")
            elif b["kind"] == "branch point":
                ax.plot(b["p"], b["value"], "ks", ms=6,
                        label=None if "bp" in seen else "branch point")
                seen.add("bp")
    rng = res.diagram.get("range")
    if rng is not None:  # the range of motion of a named angle
        lo, hi = ax.get_ylim()
        for r in rng:
            if lo - 0.1 * (hi - lo) <= r <= hi + 0.1 * (hi - lo):
                ax.axhline(r, color="0.4", lw=0.8, ls="-.",
                           label=None if "rom" in seen else "range of motion")
                seen.add("rom")
    for b in res.boundaries:
        ax.axvline(b["value"], color="tab:red", lw=0.6, ls=":",
                   label=None if "boundary" in seen else "stability boundary")
        seen.add("boundary")
    ax.set_xlabel(_axis_label(res, res.axis))
    ax.set_ylabel(f"{var} [{res.diagram.get('unit', '')}]")
    title = f"bifurcation diagram of {Path(res.case).stem}" + (f" ({res.config})" if res.config else "")
    ax.set_title(title + ": dashed = unstable, dotted = jump")
    ax.grid(True, lw=0.3)
    if n_lines > 1:
        for l in range(n_lines):
            ax.plot([], [], "-", color="0.6", lw=1.4 + 1.6 * (n_lines - 1 - l),
                    label=_line_label(res, l) or f"line {l + 1}")
        seen.add("lines")
    if seen:
        ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.02, 1.0), borderaxespad=0.0)
    fig.tight_layout()
    return fig


@_styled
def stability_chart(res):
    """Stability chart from the followed boundary curves: the first axis' critical value against
    the second parameter (one line per curve, its tolerance band as a band), the side where the
    first grid point was stable shaded."""
    fig = _figure(figsize=(7, 5.4))
    ax = fig.subplots()
    cmap = _cmap("tab10")
    along = res.curves[0]["along"] if res.curves else ""
    for i, c in enumerate(res.curves):
        pts = sorted((p for p in c["points"] if p["value"] is not None), key=lambda p: p["p2"])
        if not pts:
            continue
        x = np.array([p["p2"] for p in pts])
        y = np.array([p["value"] for p in pts])
        ax.plot(x, y, "o-", color=cmap(i % 10), ms=3, lw=1.5,
                label=f"{c['kind']} boundary ({c['stability']} of stability)")
        if c["stability"] == "loss":  # the sweep started stable: shade from its start value
            ax.fill_between(x, np.full_like(y, float(res.values[0])), y, color=cmap(i % 10),
                            alpha=0.08)
    ax.set_xlabel(_axis_label(res, along))
    ax.set_ylabel(_axis_label(res, res.axis, "critical "))
    decade_scale(ax, "x", [p["p2"] for c in res.curves for p in c["points"]])
    ax.set_title("stability chart from the followed boundaries (shaded: stable side)")
    ax.grid(True, lw=0.3, which="both")
    if res.curves:
        ax.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.13), ncol=2,
                  frameon=False)
    fig.tight_layout()
    return fig


_STAB_COLOURS = {"stable": "tab:blue", "critical": "tab:orange", "unstable": "tab:red"}


def _nice_levels(lo, hi, per_decade=(1, 2, 5)):
    """Round numbers (1, 2, 5 × 10^k) between lo and hi (both > 0)."""
    out = []
    for e in range(int(math.floor(math.log10(lo))) - 1, int(math.ceil(math.log10(hi))) + 1):
        out += [m * 10.0**e for m in per_decade if lo <= m * 10.0**e <= hi]
    return out


ZETA_GRID = (0.02, 0.05, 0.1, 0.2, 0.4, 0.7, 0.9)
# where along its ray each ζ label sits (fraction of the radius): small-ζ rays crowd the top
_ZETA_LABEL_AT = {0.02: 0.42, 0.05: 0.6, 0.1: 0.78}


def _zeta_wn_grid(ax, radius):
    """Lines of constant damping ratio ζ (rays from the origin into the left half-plane) and
    circles of constant natural frequency ω_n, labelled, drawn under the data."""
    for z in ZETA_GRID:
        ang = math.acos(z)
        x, y = -radius * z, radius * math.sin(ang)
        ax.plot([0, x], [0, y], color="0.78", lw=0.6, zorder=0)
        ax.plot([0, x], [0, -y], color="0.78", lw=0.6, zorder=0)
        f = _ZETA_LABEL_AT.get(z, 0.93)
        ax.annotate(f"ζ={z:g}", (f * x, f * y), fontsize=6, color="0.4", ha="right",
                    va="center", textcoords="offset points", xytext=(-2, 0),
                    annotation_clip=True)
    th = np.linspace(math.pi / 2, 3 * math.pi / 2, 90)
    levels = _nice_levels(radius / 20, radius, (1, 2, 5))
    if len(levels) > 6:
        levels = _nice_levels(radius / 20, radius, (1,))
    for w in levels:
        ax.plot(w * np.cos(th), w * np.sin(th), color="0.8", lw=0.5, ls=":", zorder=0)
        ax.annotate(f"ωn={w:g}", (-w, 0), fontsize=6, color="0.45", ha="left", va="top",
                    annotation_clip=True)


@_styled
def pole_map(eigenvalues, *, title="pole map", stability=None, labels=None):
    """Eigenvalues (both halves of each pair) in the s-plane over a grid of constant damping
    ratio ζ and natural frequency ω_n; numbered as the mode tables (1, 2, ...); colour by
    stability, legend outside the axes."""
    fig = _figure(figsize=(7.5, 4.8))
    ax = fig.subplots()
    s = np.asarray(eigenvalues, dtype=complex)
    radius = float(np.max(np.abs(s), initial=0.0)) * 1.08 or 1.0
    _zeta_wn_grid(ax, radius)
    seen = set()
    for k, v in enumerate(s):
        st = stability[k] if stability else None
        c = _STAB_COLOURS.get(st, "k")
        ax.plot([v.real, v.real], [v.imag, -v.imag], "x", color=c, ms=8, mew=1.6,
                label=None if st in seen else (st or "eigenvalue"), zorder=3)
        seen.add(st)
        # the number of the mode beside its upper eigenvalue; alternate sides for close ones
        ax.annotate(str(k + 1), (v.real, abs(v.imag)), textcoords="offset points",
                    xytext=(5, 5 if k % 2 == 0 else -11), fontsize=8, fontweight="bold", zorder=4)
    ax.axvline(0.0, color="k", lw=0.8)
    ax.axhline(0.0, color="k", lw=0.3)
    ax.set_xlim(-radius, max(0.12 * radius, 1.1 * float(np.max(s.real, initial=0.0))))
    ax.set_ylim(-radius, radius)
    ax.set_xlabel("Re s = −δ [1/s]")
    ax.set_ylabel("Im s = ±ω_d [rad/s]")
    ax.set_title(title)
    handles, names = ax.get_legend_handles_labels()
    if labels:
        from matplotlib.lines import Line2D

        handles += [Line2D([], [], ls="none") for _ in labels]
        names += list(labels)
    ax.legend(handles, names, fontsize=7, loc="upper left", bbox_to_anchor=(1.02, 1.0),
              borderaxespad=0.0, title="numbers = mode", title_fontsize=7)
    fig.tight_layout()
    return fig


# ---------------------------------------------------------------------------------------------
# mechanism drawings
def project_constraints(model, q, *, tol=1e-12, max_iter=30):
    """q moved onto the constraint manifold Φ(q) = 0 by Gauss–Newton with minimum-norm steps
    (q ← q − Φ_q⁺ Φ(q)); returns (q, max |Φ_k| / scale_k).  Displaying a mode by moving along it
    and projecting back keeps rigid bodies rigid (a linear displacement q₀ + a·v stretches them
    by O(a²))."""
    q = np.array(q, dtype=float)
    phi_fn, jac_fn = getattr(model, "phi", None), getattr(model, "phi_q", None)
    if phi_fn is None or jac_fn is None or not getattr(model, "n_constraints", 0):
        return q, 0.0
    scales = np.asarray(model.constraint_scales() if hasattr(model, "constraint_scales")
                        else np.ones(model.n_constraints), float)
    res = math.inf
    for _ in range(max_iter):
        phi = np.asarray(phi_fn(q), float)
        res = float(np.max(np.abs(phi) / scales, initial=0.0))
        if res <= tol:
            break
        J = jac_fn(q)
        J = J.toarray() if hasattr(J, "toarray") else np.asarray(J)
        step = np.linalg.lstsq(J, phi, rcond=None)[0]
        q = q - step
    return q, res


def _pairs_matching(model, aff, q0):
    """Names (a, b) of two points with aff = r_b − r_a (checked at two configurations), or
    None: how a spring or a rod between two named points is found from its difference map."""
    names = list(model.points)
    if len(names) > 400 or getattr(aff, "dim", 0) != 2:
        return None
    rng = np.random.default_rng(0)
    q1 = q0 + rng.standard_normal(q0.size) * max(getattr(model, "length_scale", 1.0), 1e-9) * 0.1
    P0 = np.array([model.points[n](q0) for n in names])
    P1 = np.array([model.points[n](q1) for n in names])
    d0, d1 = aff(q0), aff(q1)
    scale = max(float(np.max(np.abs(P0))), 1e-300)
    E = (np.linalg.norm(P0[None, :, :] - P0[:, None, :] - d0, axis=2)
         + np.linalg.norm(P1[None, :, :] - P1[:, None, :] - d1, axis=2))  # E[a, b]
    a, b = np.unravel_index(int(np.argmin(E)), E.shape)
    return (names[a], names[b]) if E[a, b] <= 1e-9 * scale else None


def mechanism_layout(model, q0):
    """What a planar drawing shows, found from the model by duck typing: bodies (basic points and
    body markers), fixed points, springs and dampers between named points, rods, lines that
    points slide on, torsional springs at the points their bodies share, and follower forces.
    Each entry names the element as the user did."""
    q0 = np.asarray(q0, float)
    out = {"bodies": [], "springs": [], "rods": [], "guides": [], "torsional": [], "loads": [],
           "fixed": [n for n, a in model.points.items() if a.idx.size == 0 and "." not in n]}
    for name, b in model.bodies.items():
        pts = list(b.get("points", ()))
        markers = [n for n in model.points if n.startswith(name + ".")]
        out["bodies"].append({"name": name, "points": pts, "markers": markers})
    body_dirs = {}
    for name, b in model.bodies.items():
        pts = list(b.get("points", ()))
        if len(pts) == 2:
            body_dirs[name] = pts
    for e in getattr(model, "forces", ()):
        kind = type(e).__name__
        user = element_name(getattr(e, "name", kind), part=False)
        if hasattr(e, "diff") and hasattr(e, "stiffness"):
            ends = _pairs_matching(model, e.diff, q0)
            if ends:
                out["springs"].append({"name": user, "ends": ends,
                                       "spring": float(getattr(e, "stiffness", 0)) != 0,
                                       "damper": float(getattr(e, "damping", 0)) != 0})
        elif hasattr(e, "dirs") and hasattr(e, "angle0"):
            at = _torsion_point(model, e, q0, body_dirs)
            if at is not None:
                out["torsional"].append({"name": user, "at": at})
        elif hasattr(e, "stacked") and hasattr(e, "magnitude"):
            out["loads"].append({"name": user, "element": e})
    for c in getattr(model, "constraints", ()):
        user = element_name(getattr(c, "name", ""), part=False)
        if hasattr(c, "diff") and hasattr(c, "length"):
            if any(user == b["name"] for b in out["bodies"]):
                continue  # a body's rigid length: the body is drawn
            ends = _pairs_matching(model, c.diff, q0)
            if ends:
                out["rods"].append({"name": user, "ends": ends})
        elif hasattr(c, "G") and hasattr(c, "point") and np.shape(c.G) == (1, 2):
            g = np.asarray(c.G[0], float)
            out["guides"].append({"name": user, "normal": g / np.linalg.norm(g),
                                  "offset": float(c.b[0]) / float(np.linalg.norm(g)),
                                  "point": c.point})
    return out


def _torsion_point(model, e, q0, body_dirs):
    """The point shared by the two bodies a torsional element acts between (the joint), by
    matching its directions [a; b] with the bodies' directions r_j − r_i."""
    rng = np.random.default_rng(1)
    q1 = q0 + rng.standard_normal(q0.size) * 0.1 * max(getattr(model, "length_scale", 1.0), 1e-9)
    try:
        ab0, ab1 = e.dirs(q0), e.dirs(q1)
    except Exception:  # noqa: BLE001 - a drawing aid only
        return None
    found = []
    for h in (slice(0, 2), slice(2, 4)):
        hit = None
        for name, (i, j) in body_dirs.items():
            d0 = model.points[j](q0) - model.points[i](q0)
            d1 = model.points[j](q1) - model.points[i](q1)
            c = np.linalg.norm(ab0[h]) / max(np.linalg.norm(d0), 1e-300)
            if (np.linalg.norm(ab0[h] - c * d0) + np.linalg.norm(ab1[h] - c * d1)
                    <= 1e-9 * max(np.linalg.norm(ab0[h]), 1e-300)):
                hit = name
        found.append(hit)
    b1, b2 = found
    if b2 is None:
        return None
    pts2 = set(body_dirs[b2])
    shared = pts2 & set(body_dirs[b1]) if b1 else {p for p in pts2 if model.points[p].idx.size == 0}
    return min(shared) if shared else body_dirs[b2][0]


def _zigzag(p, q, n=8, width=0.06):
    """Points of a spring symbol from p to q."""
    d = q - p
    L = np.linalg.norm(d)
    if L == 0:
        return np.array([p, q])
    t = d / L
    nrm = np.array([-t[1], t[0]])
    xs = [p, p + 0.2 * d]
    for k in range(n):
        xs.append(p + (0.2 + 0.6 * (k + 0.5) / n) * d + (1 if k % 2 == 0 else -1) * width * L * nrm)
    xs += [p + 0.8 * d, q]
    return np.array(xs)


def _draw_mechanism(ax, model, layout, q, *, colour, lw, alpha=1.0, labels=False, ms=3):
    def pt(n):  # a named point in mm
        return np.asarray(model.points[n](q), float) * 1e3

    for b in layout["bodies"]:
        if len(b["points"]) != 2:
            continue
        r = np.array([pt(b["points"][0]), pt(b["points"][1])])
        ax.plot(r[:, 0], r[:, 1], "-o", color=colour, lw=lw, ms=ms, alpha=alpha, zorder=3)
        for m in b["markers"]:  # a body marker (cuff): drawn as a rigid bracket of the body
            tri = np.array([r[0], pt(m), r[1]])
            ax.plot(tri[:, 0], tri[:, 1], "-", color=colour, lw=max(lw * 0.4, 0.5), alpha=alpha,
                    zorder=2)
    for rd in layout["rods"]:
        r = np.array([pt(rd["ends"][0]), pt(rd["ends"][1])])
        ax.plot(r[:, 0], r[:, 1], "-", color=colour, lw=lw * 0.6, alpha=alpha, zorder=2)
    for s in layout["springs"]:
        a, b = pt(s["ends"][0]), pt(s["ends"][1])
        z = _zigzag(a, b) if s["spring"] else np.array([a, b])
        ax.plot(z[:, 0], z[:, 1], "-", color=colour, lw=max(lw * 0.45, 0.6), alpha=alpha, zorder=2)
        if labels:
            mid = 0.5 * (a + b)
            kind = ("spring-damper" if s["spring"] and s["damper"] else
                    "spring" if s["spring"] else "damper")
            ax.annotate(f"{s['name']} ({kind})", mid, textcoords="offset points", xytext=(6, 0),
                        fontsize=6, color="0.3")
    for g in layout["guides"]:
        r = np.asarray(g["point"](q), float) * 1e3
        ax.plot(r[0], r[1], "s", color=colour, ms=ms + 3, mfc="none", alpha=alpha, zorder=3)
        if labels:
            ax.annotate(f"{g['name']} (slider)", r, textcoords="offset points",
                        xytext=(6, -8), fontsize=6, color="0.3")
    if labels:
        for t in layout["torsional"]:
            r = pt(t["at"])
            ax.plot(r[0], r[1], "o", ms=9, mfc="none", mec="0.5", mew=0.8, zorder=1)
        for n in layout["fixed"]:
            r = pt(n)
            ax.plot(r[0], r[1], "ks", ms=5, zorder=4)
            ax.annotate(n, r, textcoords="offset points", xytext=(-9, 3), fontsize=7)
        tors = {t["at"]: t["name"] for t in layout["torsional"]}
        for n, a in model.points.items():
            if a.idx.size and "." not in n:
                r = pt(n)
                extra = f" ({tors[n]} spring)" if n in tors else ""
                ax.annotate(n + extra, r, textcoords="offset points", xytext=(4, -9), fontsize=6,
                            color="0.25")
        for n in layout["fixed"]:
            if n in tors:
                ax.annotate(f"{tors[n]} spring", pt(n), textcoords="offset points",
                            xytext=(-9, -10), fontsize=6, color="0.25")


def _draw_guides(ax, layout, q, extent):
    """Each guide as a dashed line across the drawing (the line the point slides on)."""
    for g in layout["guides"]:
        nrm = g["normal"]
        t = np.array([-nrm[1], nrm[0]])
        base = nrm * g["offset"] * 1e3
        ax.plot(*np.array([base - extent * t, base + extent * t]).T, "--", color="0.55", lw=0.8,
                zorder=1)


def _draw_loads(ax, model, layout, q, L_mm):
    for ld in layout["loads"]:
        e = ld["element"]
        v = np.asarray(e.stacked(q), float)
        r, u = v[:2] * 1e3, v[2:4]
        mag = float(e.magnitude)
        d = (np.sign(mag) if mag else 1.0) * u / max(np.linalg.norm(u), 1e-300) * 0.25 * L_mm
        ax.annotate("", xy=r + d, xytext=r,
                    arrowprops={"arrowstyle": "->", "color": "tab:green", "lw": 1.2,
                                "ls": "-" if mag else "--"}, zorder=4)
        ax.annotate(f"{ld['name']} ({mag:g} N, follower)", r + d, fontsize=6, color="tab:green",
                    textcoords="offset points", xytext=(3, -8))


@_styled
def mechanism_modes(model, q0, shapes, labels, *, amplitude=0.12, title="", eigenvalues=None,
                    kinds=None):
    """The mechanism at equilibrium (black) with each mode shape superposed (one panel a mode).

    Every element the layout finds is drawn (bodies, body markers, rods, springs and dampers as
    zigzags, sliders on their dashed guides, torsional springs at their joints, follower loads
    as arrows).  A displaced configuration is q₀ + a·L·Re(e^{−iφ} v)/max|v| (a = ``amplitude``,
    L the model's size, φ the phase of the largest component) projected back onto Φ(q) = 0
    (:func:`project_constraints`), so rigid bodies stay rigid.  An oscillatory mode is drawn at
    ±a (red/blue); a real mode (``eigenvalues`` given, Im s = 0) is not an oscillation: it is
    drawn as its decay (or growth) e^{st} at t = 0, τ, 2τ, 3τ with τ = 1/|s|, fading.  With
    ``kinds`` (the modes' kinds), only "overdamped" and "divergence" modes are drawn so (a
    rigid-body mode's s ≈ 0 is not a decay).
    """
    def is_real(k):
        if eigenvalues is None:
            return False
        s = complex(eigenvalues[k])
        if kinds is not None:
            return kinds[k] in ("overdamped", "divergence") and s.real != 0
        return s.imag == 0.0 and s.real != 0.0

    n = len(labels)
    cols = min(n, 3) or 1
    rows = max(1, math.ceil(n / cols))
    L = float(model.length_scale)
    q0 = np.asarray(q0, float)
    layout = mechanism_layout(model, q0)
    pts0 = np.array([model.points[nm](q0) for nm in model.points]) * 1e3
    span = np.ptp(pts0, axis=0) + 0.5 * float(np.max(np.ptp(pts0, axis=0)))
    ratio = float(span[0] / max(span[1], 1e-300))  # panel width / height of the drawing
    panel_h = 3.9
    panel_w = min(max(panel_h * ratio, 2.4), 6.0) + 1.0
    fig = _figure(figsize=(panel_w * cols, (panel_h + 0.5) * rows + 0.7))
    axes = fig.subplots(rows, cols, squeeze=False)
    extent = 2.0 * float(np.max(np.ptp(pts0, axis=0))) + 1.0
    for k in range(rows * cols):
        ax = axes[k // cols][k % cols]
        if k >= n:
            ax.axis("off")
            continue
        v = np.asarray(shapes[:, k])
        j = int(np.argmax(np.abs(v)))
        vr = (v * np.exp(-1j * np.angle(v[j]))).real if np.iscomplexobj(v) else v
        vr = vr / max(np.max(np.abs(vr)), 1e-300)
        _draw_guides(ax, layout, q0, extent)
        s = None if eigenvalues is None else complex(eigenvalues[k])
        if is_real(k):
            # a real mode: the shape decays (s < 0) or grows (s > 0) without oscillating
            growth = s.real > 0
            for i, t in enumerate((0.0, 1.0, 2.0, 3.0)):
                a = amplitude * math.exp((1 if growth else -1) * (t - (3.0 if growth else 0.0)))
                qd, _ = project_constraints(model, q0 + a * L * vr)
                _draw_mechanism(ax, model, layout, qd, colour="tab:purple", lw=1.1,
                                alpha=0.9 - 0.2 * (i if not growth else 3 - i))
        else:
            for sign, col in ((1.0, "tab:red"), (-1.0, "tab:blue")):
                qd, _ = project_constraints(model, q0 + sign * amplitude * L * vr)
                _draw_mechanism(ax, model, layout, qd, colour=col, lw=1.1, alpha=0.85)
        _draw_mechanism(ax, model, layout, q0, colour="k", lw=2.2, labels=True)
        _draw_loads(ax, model, layout, q0, L * 1e3)
        lim_x = (pts0[:, 0].min(), pts0[:, 0].max())
        lim_y = (pts0[:, 1].min(), pts0[:, 1].max())
        pad = 0.25 * max(lim_x[1] - lim_x[0], lim_y[1] - lim_y[0])
        ax.set_xlim(lim_x[0] - pad, lim_x[1] + pad)
        ax.set_ylim(lim_y[0] - pad, lim_y[1] + pad)
        ax.set_aspect("equal", adjustable="box")
        ax.set_title(labels[k], fontsize=8)
        ax.set_xlabel("x [mm]")
        ax.set_ylabel("y [mm]")
        ax.grid(True, lw=0.3)
    from matplotlib.lines import Line2D

    handles = [Line2D([], [], color="k", lw=2.2, label="equilibrium"),
               Line2D([], [], color="tab:red", lw=1.1, label="+ mode (oscillatory)"),
               Line2D([], [], color="tab:blue", lw=1.1, label="− mode (half a period later)")]
    if any(is_real(k) for k in range(n)):
        handles.append(Line2D([], [], color="tab:purple", lw=1.1,
                              label="real mode: e^{st} at t = 0, τ, 2τ, 3τ (fading)"))
    if layout["guides"]:
        handles.append(Line2D([], [], color="0.55", ls="--", lw=0.8, label="slider guide"))
    if layout["torsional"]:
        handles.append(Line2D([], [], ls="none", marker="o", mfc="none", mec="0.5", ms=8,
                              label="torsional spring-damper"))
    fig.legend(handles=handles, loc="lower center", ncol=min(len(handles), 4), fontsize=7,
               frameon=False)
    if title:
        fig.suptitle(title)
    fig.tight_layout(rect=(0, 0.06 if rows == 1 else 0.03, 1, 1))
    return fig


def _slug(text):
    return re.sub(r"[^A-Za-z0-9_.-]+", "_", text).strip("_") or "case"


def plot_check(result, directory) -> list:
    """Write ``<case>_mode<k>.png`` per simulated mode of a time-domain check ``result`` into
    ``directory`` (one figure per mode: Re η with the fitted and predicted envelopes, and the
    dominant coordinate); returns the paths."""
    out = Path(directory)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise CaseError(f"cannot create the plot directory: {exc.strerror or exc}",
                        file=str(out), element="--plot") from None
    paths = []
    for m in result.modes:
        if m.skipped or m.t.size == 0:
            continue
        fig = _figure(figsize=(8, 6), constrained_layout=True)
        ax1, ax2 = fig.subplots(2, 1, sharex=True)
        t = m.t
        a0 = abs(m.eta[0])
        ax1.plot(t, m.eta.real, lw=0.8, color="C0", label="modal coordinate Re η (simulation)")
        fit = m.fit_amplitude * np.exp(-m.measured_delta * t)
        pred = a0 * np.exp(-m.predicted_delta * t)
        for sign in (1, -1):
            ax1.plot(t, sign * fit, color="C1", lw=1.6,
                     label=f"fitted envelope, δ = {m.measured_delta:.5g}" if sign > 0 else None)
            ax1.plot(t, sign * pred, color="k", lw=1.0, ls="--",
                     label=f"predicted envelope, δ = {m.predicted_delta:.5g}" if sign > 0 else None)
        verdict = "pass" if m.passed else "FAIL"
        ax1.set_title(f"{result.name}: mode {m.index} ({m.kind}), {verdict}\n"
                      f"ω pred {m.predicted_omega:.6g}, meas {m.measured_omega:.6g} "
                      f"(rel. err. {m.rel_error_omega:.2e}); δ rel. err. {m.rel_error_delta:.2e}",
                      fontsize=10)
        ax1.set_ylabel("η")
        lo, hi = ax1.get_ylim()
        ax1.set_ylim(lo, hi + 0.6 * (hi - lo))  # room for the legend above the curves
        ax1.legend(fontsize=8, loc="upper right")
        ax2.plot(t, m.response, lw=0.8, color="C2")
        ax2.set_ylabel(f"{m.coordinate} − equilibrium")
        ax2.set_xlabel("t [s]")
        paths.append(save(fig, out / f"{_slug(result.name)}_mode{m.index}.png", dpi=110,
                          element="--plot"))
    return paths


@_styled
def speed_accuracy(res):
    """Error against wall time, one line per method of a :func:`mbseig.bench.run_bench` result."""
    fig = _figure(figsize=(9, 6))
    ax = fig.subplots()
    markers = "os^vD<>pPX*h"
    rows = [r for r in res["rows"] if r["section"] in ("dense", "structured", "partial", "jacobians")
            and isinstance(r.get("error"), float) and math.isfinite(r["error"])]
    methods = list(dict.fromkeys(f"{r['section']}: {r['method']}" for r in rows))
    colors = _cmap("tab20").colors  # one colour per method (tab10 repeats after ten)
    for k, m in enumerate(methods):
        pts = [r for r in rows if f"{r['section']}: {r['method']}" == m]
        x = [r["time"] for r in pts]
        y = [max(r["error"], 1e-17) for r in pts]
        sizes = [r["n"] for r in pts]
        label = f"{m} (n = {min(sizes):g}…{max(sizes):g})" if len(pts) > 1 else f"{m} (n = {sizes[0]:g})"
        colour = colors[(2 * k) % 20 if k < 10 else (2 * k + 1) % 20]
        ax.plot(x, y, linestyle="-", label=label, alpha=0.85, color=colour, lw=1.2,
                marker=markers[k % len(markers)], ms=3)
        # the size as the marker's area (no text labels to collide): larger n, larger marker
        ax.scatter(x, y, s=[8 + 10 * math.log10(max(r["n"], 1)) ** 2 for r in pts],
                   marker=markers[k % len(markers)], color=colour, alpha=0.6, zorder=3)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("wall time [s] (median)")
    ax.set_ylabel("relative error (vs closed form / complex step)")
    ax.set_title("mbseig: error against wall time (marker size grows with the problem size n)")
    ax.grid(True, which="both", alpha=0.3)
    if methods:
        ax.legend(fontsize=7, loc="center left", bbox_to_anchor=(1.01, 0.5))
    fig.tight_layout()
    return fig
