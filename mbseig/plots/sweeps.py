"""Figures of sweeps: root locus, modes against the parameter, stability maps and charts, the
bifurcation diagram."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from .common import (
    LINESTYLES,
    axis_label,
    colormap,
    decade_scale,
    figure,
    line_label,
    mode_numbers,
    styled,
)


def _tracks(res):
    """(line style, track, mode number, colour, tolerance) of every listed track of every line:
    one colour a mode numbered as the mode tables at the first point, one line style a line;
    the tolerance is each point's stability tolerance of that eigenvalue (None when the result
    carries none)."""
    cmap = colormap("tab10")
    tols = getattr(res, "tolerances_track", None)
    for li, S in enumerate(res.tracks):
        numbers = mode_numbers(res, li)
        ls = LINESTYLES[li % len(LINESTYLES)]
        T = None if tols is None or li >= len(tols) else np.asarray(tols[li], float)
        for j in res.listed_tracks(S):
            m = numbers.get(j, j + 1)
            yield ls, S[:, j], m, cmap((m - 1) % 10), None if T is None else T[:, j]


def banded_real(col, tol):
    """Re s with every value inside its error band (|Re s| ≤ tol, the eigenvalue's stability
    tolerance, as the tables call such a mode "critical") drawn as 0: a figure shows the
    physics, not the rounding residue."""
    re = np.asarray(col).real.copy()
    if tol is not None:
        inside = np.abs(re) <= np.nan_to_num(np.asarray(tol, float), nan=0.0)
        re[inside] = 0.0
    return re


def physical_limits(lo, hi, scale, *, fraction=0.05):
    """Axis limits [lo, hi] padded, at least ±``fraction``·``scale`` around 0, so values within
    their error band (drawn as 0) are not blown up to fill the axis."""
    w = fraction * scale if scale > 0 else 1.0
    lo, hi = min(lo, -w), max(hi, w)
    pad = 0.06 * (hi - lo)
    return lo - pad, hi + pad


def _mode_legend(ax, res, modes_seen, extra):
    """The legend outside the axes: a colour per mode (numbered at the first value), a line
    style per line of the other axes, then ``extra`` handles."""
    from matplotlib.lines import Line2D

    handles = [Line2D([], [], color=c, lw=1.5, label=f"mode {m}")
               for m, c in sorted(modes_seen.items())]
    if len(res.tracks) > 1:
        handles += [Line2D([], [], color="0.3", linestyle=LINESTYLES[li % len(LINESTYLES)],
                           label=line_label(res, li)) for li in range(len(res.tracks))]
    ax.legend(handles=handles + extra, fontsize=7, loc="upper left", bbox_to_anchor=(1.02, 1.0),
              borderaxespad=0.0, title=f"modes numbered at {res.axis} = {res.values[0]:g}",
              title_fontsize=7)


@styled
def root_locus(res):
    """Tracked eigenvalues in the s-plane along the first axis: one colour a mode (numbered as
    the mode tables at the first point), one line style a line of the other axes; both halves
    of a pair drawn in the same colour; dot = first value; x = located boundary.  Legend outside
    the axes."""
    from matplotlib.lines import Line2D

    fig = figure(layout="constrained", figsize=(8.5, 5))
    ax = fig.subplots()
    modes_seen = {}
    re_all, s_max, band = [], 0.0, 0.0
    for ls, col, m, c, tol in _tracks(res):
        ok = ~np.isnan(col)
        if not ok.any():
            continue
        modes_seen.setdefault(m, c)
        re = banded_real(col, tol)
        re_all.append(re[ok])
        s_max = max(s_max, float(np.max(np.abs(col[ok]))))
        if tol is not None:
            band = max(band, float(np.nanmax(np.asarray(tol, float)[ok])))
        for sign in ((1, -1) if np.any(col.imag[ok] != 0) else (1,)):
            ax.plot(re[ok], sign * col.imag[ok], linestyle=ls, color=c, lw=1.1, alpha=0.85)
        first = np.flatnonzero(ok)[0]
        ax.plot(re[first], col.imag[first], "o", color=c, ms=3.5)
    for b in res.boundaries:
        ax.plot(b["eigenvalue"][0], b["eigenvalue"][1], "kx", ms=8, mew=1.5)
        ax.plot(b["eigenvalue"][0], -b["eigenvalue"][1], "kx", ms=8, mew=1.5)
        re_all.append(np.array([b["eigenvalue"][0]]))
    if re_all:
        re_all = np.concatenate(re_all)
        ax.set_xlim(*physical_limits(float(re_all.min()), float(re_all.max()), s_max))
    if band > 0:
        ax.axvspan(-band, band, color="0.75", lw=0, zorder=0)
    ax.axvline(0.0, color="k", lw=0.8)
    ax.set_xlabel("Re s = −δ [1/s]")
    ax.set_ylabel("Im s = ±ω_d [rad/s]")
    title = f"root locus of {Path(res.case).stem}" + (f" ({res.config})" if res.config else "")
    unit = (getattr(res, "units", None) or {}).get(res.axis)
    unit = f" {unit}" if unit and unit != "1" else ""
    ax.set_title(f"{title}: {res.axis} from {res.values[0]:g} to {res.values[-1]:g}{unit}")
    ax.grid(True, lw=0.3)
    _mode_legend(ax, res, modes_seen, [
        Line2D([], [], ls="none", marker="o", color="0.3", ms=3.5,
               label=f"{res.axis} = {res.values[0]:g}"),
        Line2D([], [], ls="none", marker="x", color="k", ms=7, label="stability boundary"),
        Line2D([], [], color="0.75", lw=4, label=f"|Re s| ≤ tol (≤ {band:.1g} 1/s): drawn as 0")])
    return fig


@styled
def modes_vs_parameter(res):
    """Damped frequency ω_d/2π and damping δ of each mode against the first axis (one colour a
    mode numbered as the mode tables at the first point, one line style a line of the other
    axes); legend outside the axes; log scales where the values span decades."""
    from matplotlib.lines import Line2D

    fig = figure(layout="constrained", figsize=(8.5, 6))
    a1, a2 = fig.subplots(2, 1, sharex=True)
    x = np.asarray(res.values, float)
    modes_seen = {}
    for ls, col, m, c, tol in _tracks(res):
        modes_seen.setdefault(m, c)
        a1.plot(x, np.abs(col.imag) / (2 * math.pi), linestyle=ls, color=c, lw=1.1)
        a2.plot(x, -banded_real(col, tol), linestyle=ls, color=c, lw=1.1)
    for b in res.boundaries:
        a2.axvline(b["value"], color="r", lw=0.8, ls="--")
    a2.axhline(0.0, color="k", lw=0.8)
    a1.set_ylabel("damped frequency ω_d/2π [Hz]")
    a2.set_ylabel("damping δ = −Re s [1/s] (0 within its error band)")
    a2.set_xlabel(axis_label(res, res.axis))
    a2.set_yscale("symlog", linthresh=1.0)
    decade_scale(a2, "x", x)
    a1.grid(True, lw=0.3)
    a2.grid(True, lw=0.3)
    a1.set_title("modes tracked by MAC; red dashed: stability boundaries")
    _mode_legend(a1, res, modes_seen, [
        Line2D([], [], color="r", ls="--", lw=0.8, label="stability boundary")])
    return fig


@styled
def stability_map(res):
    """Two-parameter map: spectral abscissa max Re s (colour), the α = 0 contour and the located
    boundaries (points)."""
    fig = figure(layout="constrained", figsize=(7.5, 5.4))
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
    ax.set_xlabel(axis_label(res, res.axes[0][0]))
    ax.set_ylabel(axis_label(res, res.axes[1][0]))
    ax.set_title("stability map (spectral abscissa on the grid)")
    handles = [Line2D([], [], color="k", lw=1, label="α = max Re s = 0 (grid contour)"),
               Line2D([], [], color="k", ls="none", marker="o", ms=4,
                      label="boundary located by root finding")]
    if getattr(res, "curves", None):
        handles.append(Line2D([], [], color="tab:green", lw=1.5, label="boundary followed across "
                              + res.axes[1][0]))
    fig.legend(handles=handles, loc="outside lower center", ncol=len(handles), fontsize=7,
               frameon=False)
    return fig


STAB_STYLE = {"stable": ("tab:blue", "-"), "critical": ("tab:orange", "-"),
               "unstable": ("tab:red", "--")}


@styled
def bifurcation_diagram(res):
    """The followed branches: the swept parameter against the diagram variable (a named angle or
    a coordinate), solid where stable (blue) or critical (orange), dashed red where unstable;
    folds (triangles), branch points (squares) and jumps (dotted) marked."""
    fig = figure(layout="constrained", figsize=(8.5, 5))
    ax = fig.subplots()
    var = res.diagram.get("variable", "")
    seen = set()
    n_lines = len(res.branches)
    for li, branch in enumerate(res.branches):
        # lines that share a branch (parameters that do not enter the statics) would hide each
        # other: the first line is drawn widest, each next one narrower on top of it
        lw = 1.4 + 1.6 * (n_lines - 1 - li)
        pts = [b for b in branch if b.get("value") is not None]
        for a, b in zip(pts, pts[1:], strict=False):  # consecutive pairs: one fewer
            if a["segment"] != b["segment"]:
                ax.plot([a["p"], b["p"]], [a["value"], b["value"]], ":", color="0.6", lw=0.8)
                continue
            st = (b.get("verdict") or b.get("static") or "stable")
            st = st if st in STAB_STYLE else "critical"
            color, ls = STAB_STYLE[st]
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
    ax.set_xlabel(axis_label(res, res.axis))
    ax.set_ylabel(f"{var} [{res.diagram.get('unit', '')}]")
    title = (f"bifurcation diagram of {Path(res.case).stem}"
             + (f" ({res.config})" if res.config else ""))
    ax.set_title(title + ": dashed = unstable, dotted = jump")
    ax.grid(True, lw=0.3)
    if n_lines > 1:
        for li in range(n_lines):
            ax.plot([], [], "-", color="0.6", lw=1.4 + 1.6 * (n_lines - 1 - li),
                    label=line_label(res, li) or f"line {li + 1}")
        seen.add("lines")
    if seen:
        ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.02, 1.0), borderaxespad=0.0)
    return fig


@styled
def stability_chart(res):
    """Stability chart from the followed boundary curves: the first axis' critical value against
    the second parameter (one line per curve, its tolerance band as a band), the side where the
    first grid point was stable shaded."""
    fig = figure(layout="constrained", figsize=(7, 5.4))
    ax = fig.subplots()
    cmap = colormap("tab10")
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
    ax.set_xlabel(axis_label(res, along))
    ax.set_ylabel(axis_label(res, res.axis, "critical "))
    decade_scale(ax, "x", [p["p2"] for c in res.curves for p in c["points"]])
    ax.set_title("stability chart from the followed boundaries (shaded: stable side)")
    ax.grid(True, lw=0.3, which="both")
    if res.curves:
        ax.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.13), ncol=2,
                  frameon=False)
    return fig


STAB_COLOURS = {"stable": "tab:blue", "critical": "tab:orange", "unstable": "tab:red"}
