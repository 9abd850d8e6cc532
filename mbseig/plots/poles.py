"""Pole maps on a ζ/ω_n grid, the time-domain check figure and the speed-accuracy chart."""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np

from ..display import fmt
from ..errors import CaseError
from .common import (
    colormap,
    figure,
    nice_levels,
    save,
    slug,
    styled,
)
from .sweeps import (
    STAB_COLOURS,
)

ZETA_GRID = (0.02, 0.05, 0.1, 0.2, 0.4, 0.7, 0.9)
#: a coordinate name of mbseig's own: a body's unit-vector component, a beam node by index
INTERNAL_NAME = re.compile(r"\.[uvw]\.|\.n\d+\b")


def _bound(m, name):
    x = float(getattr(m, name, math.nan))
    return x if math.isfinite(x) else None


# where along its ray each ζ label sits (fraction of the radius): small-ζ rays crowd the top
_ZETA_LABEL_AT = {0.02: 0.42, 0.05: 0.6, 0.1: 0.78}


def zeta_wn_grid(ax, radius):
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
    levels = nice_levels(radius / 20, radius, (1, 2, 5))
    if len(levels) > 6:
        levels = nice_levels(radius / 20, radius, (1,))
    for w in levels:
        ax.plot(w * np.cos(th), w * np.sin(th), color="0.8", lw=0.5, ls=":", zorder=0)
        ax.annotate(f"ωn={w:g}", (-w, 0), fontsize=6, color="0.45", ha="left", va="top",
                    annotation_clip=True)


@styled
def pole_map(eigenvalues, *, title="pole map", stability=None, labels=None):
    """Eigenvalues (both halves of each pair) in the s-plane over a grid of constant damping
    ratio ζ and natural frequency ω_n; numbered as the mode tables (1, 2, ...); colour by
    stability, legend outside the axes."""
    fig = figure(layout="constrained", figsize=(7.5, 4.8))
    ax = fig.subplots()
    s = np.asarray(eigenvalues, dtype=complex)
    radius = float(np.max(np.abs(s), initial=0.0)) * 1.08 or 1.0
    zeta_wn_grid(ax, radius)
    seen = set()
    for k, v in enumerate(s):
        st = stability[k] if stability else None
        c = STAB_COLOURS.get(st, "k")
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
    return fig


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
        fig = figure(layout="constrained", figsize=(8, 6))
        ax1, ax2 = fig.subplots(2, 1, sharex=True)
        t = m.t
        a0 = abs(m.eta[0])
        ax1.plot(t, m.eta.real, lw=0.8, color="C0", label="modal coordinate Re η (simulation)")
        fit = m.fit_amplitude * np.exp(-m.measured_delta * t)
        pred = a0 * np.exp(-m.predicted_delta * t)
        # numbers as read (the zero rule): predictions within their bounds, measurements
        # within what the run resolves of them, are 0
        bd, bw = _bound(m, "bound_delta"), _bound(m, "bound_omega")
        rd, rw = _bound(m, "resolution_delta"), _bound(m, "resolution_omega")
        for sign in (1, -1):
            ax1.plot(t, sign * fit, color="C1", lw=1.6,
                     label=f"fitted envelope, δ = {fmt(m.measured_delta, rd, '.5g')} 1/s"
                     if sign > 0 else None)
            ax1.plot(t, sign * pred, color="k", lw=1.0, ls="--",
                     label=f"predicted envelope, δ = {fmt(m.predicted_delta, bd, '.5g')} 1/s"
                     if sign > 0 else None)
        verdict = "pass" if m.passed else "FAIL"
        rel_d = "–" if not math.isfinite(m.rel_error_delta) else f"{m.rel_error_delta:.2e}"
        ax1.set_title(f"{result.name}: mode {m.index} ({m.kind}), {verdict}\n"
                      f"ω pred {fmt(m.predicted_omega, bw)}, meas {fmt(m.measured_omega, rw)} "
                      f"rad/s (rel. err. {m.rel_error_omega:.2e}); δ rel. err. {rel_d}",
                      fontsize=10)
        ax1.set_ylabel("η")
        lo, hi = ax1.get_ylim()
        ax1.set_ylim(lo, hi + 0.6 * (hi - lo))  # room for the legend above the curves
        ax1.legend(fontsize=8, loc="upper right")
        ax2.plot(t, m.response, lw=0.8, color="C2")
        # a natural coordinate of mbseig's own (a unit-vector component, a beam node) is not
        # named: the user wrote no such name
        named = m.coordinate and not INTERNAL_NAME.search(m.coordinate)
        ax2.set_ylabel(f"{m.coordinate} − equilibrium" if named else
                       "largest coordinate − equilibrium")
        ax2.set_xlabel("t [s]")
        paths.append(save(fig, out / f"{slug(result.name)}_mode{m.index}.png", dpi=110,
                          element="--plot"))
    return paths


@styled
def speed_accuracy(res):
    """Error against wall time, one line per method of a :func:`mbseig.bench.run_bench` result."""
    fig = figure(layout="constrained", figsize=(9, 6))
    ax = fig.subplots()
    markers = "os^vD<>pPX*h"
    rows = [r for r in res["rows"]
            if r["section"] in ("dense", "structured", "partial", "jacobians")
            and isinstance(r.get("error"), float) and math.isfinite(r["error"])]
    methods = list(dict.fromkeys(f"{r['section']}: {r['method']}" for r in rows))
    colors = colormap("tab20").colors  # one colour per method (tab10 repeats after ten)
    for k, m in enumerate(methods):
        pts = [r for r in rows if f"{r['section']}: {r['method']}" == m]
        x = [r["time"] for r in pts]
        y = [max(r["error"], 1e-17) for r in pts]
        sizes = [r["n"] for r in pts]
        label = (f"{m} (n = {min(sizes):g}…{max(sizes):g})" if len(pts) > 1
                 else f"{m} (n = {sizes[0]:g})")
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
    return fig
