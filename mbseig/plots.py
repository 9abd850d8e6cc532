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


@_styled
def root_locus(res):
    """Tracked eigenvalues in the s-plane, coloured by track, along the first axis (all lines)."""
    fig = _figure(figsize=(7, 5))
    ax = fig.subplots()
    cmap = _cmap("tab10")
    for l, S in enumerate(res.tracks):
        for n, j in enumerate(range(S.shape[1])):
            col = S[:, j]
            ok = ~np.isnan(col)
            ax.plot(col.real[ok], col.imag[ok], "-", color=cmap(j % 10), lw=1, alpha=0.8)
            if ok.any():
                first = np.flatnonzero(ok)[0]
                ax.plot(col.real[first], col.imag[first], "o", color=cmap(j % 10), ms=3)
    for b in res.boundaries:
        ax.plot(b["eigenvalue"][0], b["eigenvalue"][1], "kx", ms=8)
        ax.plot(b["eigenvalue"][0], -b["eigenvalue"][1], "kx", ms=8)
    ax.axvline(0.0, color="k", lw=0.8)
    ax.set_xlabel("Re s [1/s]")
    ax.set_ylabel("Im s [rad/s]")
    title = f"root locus of {Path(res.case).stem}" + (f" ({res.config})" if res.config else "")
    ax.set_title(f"{title}: {res.axis} from {res.values[0]:g} (dot) to {res.values[-1]:g}; x = boundary")
    ax.grid(True, lw=0.3)
    fig.tight_layout()
    return fig


@_styled
def modes_vs_parameter(res):
    """Frequency ω/2π and damping δ of each listed track against the first axis."""
    fig = _figure(figsize=(7, 6))
    a1, a2 = fig.subplots(2, 1, sharex=True)
    cmap = _cmap("tab10")
    x = res.values
    for l, S in enumerate(res.tracks):
        for j in res.listed_tracks(S):
            col = S[:, j]
            label = f"track {j}" if len(res.tracks) == 1 else None
            a1.plot(x, np.abs(col.imag) / (2 * math.pi), "-", color=cmap(j % 10), lw=1, label=label)
            a2.plot(x, -col.real, "-", color=cmap(j % 10), lw=1)
    for b in res.boundaries:
        a2.axvline(b["value"], color="r", lw=0.8, ls="--")
    a2.axhline(0.0, color="k", lw=0.8)
    a1.set_ylabel("frequency ω/2π [Hz]")
    a2.set_ylabel("damping δ = −Re s [1/s]")
    a2.set_xlabel(res.axis)
    a2.set_yscale("symlog", linthresh=1.0)
    if len(res.tracks) == 1:
        a1.legend(fontsize=7, ncol=3)
    a1.grid(True, lw=0.3)
    a2.grid(True, lw=0.3)
    a1.set_title("tracked modes (MAC); dashed: stability boundaries")
    fig.tight_layout()
    return fig


@_styled
def stability_map(res):
    """Two-parameter map: spectral abscissa max Re s (colour), the α = 0 contour and the located
    boundaries (points)."""
    fig = _figure(figsize=(7, 5))
    ax = fig.subplots()
    x, y = res.axes[0][1], res.axes[1][1]
    A = res.abscissa_grid()  # (len(x), len(y))
    lim = float(np.nanmax(np.abs(A))) or 1.0
    from matplotlib.colors import SymLogNorm

    mesh = ax.pcolormesh(x, y, A.T, shading="nearest", cmap="RdBu_r",
                         norm=SymLogNorm(linthresh=max(lim * 1e-3, 1e-12), vmin=-lim, vmax=lim))
    fig.colorbar(mesh, ax=ax, label="spectral abscissa max Re s [1/s] (red: unstable)")
    if A.shape[0] > 1 and A.shape[1] > 1 and np.nanmin(A) < 0 < np.nanmax(A):
        ax.contour(x, y, A.T, levels=[0.0], colors="k", linewidths=1)
    for b in res.boundaries:
        ax.plot(b["value"], b["fixed"][res.axes[1][0]], "ko", ms=4)
    for c in getattr(res, "curves", []) or []:
        pts = [p for p in c["points"] if p["value"] is not None]
        ax.plot([p["value"] for p in pts], [p["p2"] for p in pts], "-", color="tab:green", lw=1.5)
    ax.set_xlabel(res.axes[0][0])
    ax.set_ylabel(res.axes[1][0])
    ax.set_title("stability map: black line α = 0, dots = boundaries located by root finding"
                 + (", green = followed boundary" if getattr(res, "curves", None) else ""))
    fig.tight_layout()
    return fig


_STAB_STYLE = {"stable": ("tab:blue", "-"), "critical": ("tab:orange", "-"),
               "unstable": ("tab:red", "--")}


@_styled
def bifurcation_diagram(res):
    """The followed branches: the swept parameter against the diagram variable (a named angle or
    a coordinate), solid where stable (blue) or critical (orange), dashed red where unstable;
    folds (triangles), branch points (squares) and jumps (dotted) marked."""
    fig = _figure(figsize=(7, 5))
    ax = fig.subplots()
    var = res.diagram.get("variable", "")
    seen = set()
    for l, branch in enumerate(res.branches):
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
            ax.plot([a["p"], b["p"]], [a["value"], b["value"]], ls, color=color, lw=1.4,
                    label=label)
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
    ax.set_xlabel(res.axis)
    ax.set_ylabel(f"{var} [{res.diagram.get('unit', '')}]")
    title = f"bifurcation diagram of {Path(res.case).stem}" + (f" ({res.config})" if res.config else "")
    ax.set_title(title + ": dashed = unstable, dotted = jump")
    ax.grid(True, lw=0.3)
    if seen:
        ax.legend(fontsize=7)
    fig.tight_layout()
    return fig


@_styled
def stability_chart(res):
    """Stability chart from the followed boundary curves: the first axis' critical value against
    the second parameter (one line per curve, its tolerance band as a band), the side where the
    first grid point was stable shaded."""
    fig = _figure(figsize=(7, 5))
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
    ax.set_xlabel(along)
    ax.set_ylabel(f"critical {res.axis}")
    xs = [p["p2"] for c in res.curves for p in c["points"]]
    if xs and min(xs) >= 0 and max(xs) > 0 and max(xs) / max(min(x for x in xs if x > 0), 1e-300) > 100:
        ax.set_xscale("symlog", linthresh=min(x for x in xs if x > 0))
    ax.set_title("stability chart from the followed boundaries (shaded: stable side)")
    ax.grid(True, lw=0.3)
    if res.curves:
        ax.legend(fontsize=7)
    fig.tight_layout()
    return fig


@_styled
def pole_map(eigenvalues, *, title="pole map", stability=None):
    """Eigenvalues (both halves of each pair) in the s-plane."""
    fig = _figure(figsize=(6, 4.5))
    ax = fig.subplots()
    s = np.asarray(eigenvalues)
    colors = {"stable": "tab:blue", "critical": "tab:orange", "unstable": "tab:red"}
    for k, v in enumerate(s):
        c = colors.get(stability[k], "k") if stability else "k"
        ax.plot([v.real, v.real], [v.imag, -v.imag], "x", color=c, ms=8)
        ax.annotate(str(k + 1), (v.real, abs(v.imag)), textcoords="offset points", xytext=(4, 4))
    ax.axvline(0.0, color="k", lw=0.8)
    ax.axhline(0.0, color="k", lw=0.3)
    ax.set_xlabel("Re s [1/s]")
    ax.set_ylabel("Im s [rad/s]")
    ax.set_title(title)
    ax.grid(True, lw=0.3)
    fig.tight_layout()
    return fig


@_styled
def mechanism_modes(model, q0, shapes, labels, *, amplitude=0.15, title=""):
    """The mechanism at equilibrium (black) with each mode shape superposed (one panel a mode).

    A mode shape (complex, full coordinates) is drawn at the phase of its largest component:
    q = q0 ± a·L·Re(e^{-iφ} v)/max|v| with a = ``amplitude`` and L the model's size.
    """
    n = len(labels)
    cols = min(n, 3) or 1
    rows = max(1, math.ceil(n / cols))
    fig = _figure(figsize=(4.2 * cols, 3.8 * rows))
    axes = fig.subplots(rows, cols, squeeze=False)
    L = model.length_scale

    def draw(ax, q, **kw):
        for b in model.bodies.values():
            pi, pj = b["points"]
            r = np.array([model.points[pi](q), model.points[pj](q)])
            ax.plot(r[:, 0] * 1e3, r[:, 1] * 1e3, "-o", ms=3, **kw)
        for name, aff in model.points.items():
            if aff.idx.size == 0 and "." not in name:
                r = aff(q)
                ax.plot(r[0] * 1e3, r[1] * 1e3, "ks", ms=4)
                ax.annotate(name, (r[0] * 1e3, r[1] * 1e3), textcoords="offset points",
                            xytext=(3, 3), fontsize=7)

    for k in range(rows * cols):
        ax = axes[k // cols][k % cols]
        if k >= n:
            ax.axis("off")
            continue
        v = np.asarray(shapes[:, k])
        j = int(np.argmax(np.abs(v)))
        vr = (v * np.exp(-1j * np.angle(v[j]))).real if np.iscomplexobj(v) else v
        vr = vr / max(np.max(np.abs(vr)), 1e-300)
        draw(ax, q0, color="k", lw=2)
        draw(ax, q0 + amplitude * L * vr, color="tab:red", lw=1, alpha=0.8)
        draw(ax, q0 - amplitude * L * vr, color="tab:blue", lw=1, alpha=0.8)
        ax.set_aspect("equal")
        ax.set_title(labels[k], fontsize=8)
        ax.set_xlabel("x [mm]")
        ax.set_ylabel("y [mm]")
        ax.grid(True, lw=0.3)
    if title:
        fig.suptitle(title)
    fig.tight_layout()
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
        ax.plot(x, y, marker=markers[k % len(markers)], linestyle="-", label=m, alpha=0.85,
                color=colors[(2 * k) % 20 if k < 10 else (2 * k + 1) % 20])
        for r in pts:
            ax.annotate(f"{r['n']:g}", (r["time"], max(r["error"], 1e-17)), fontsize=6,
                        xytext=(3, 3), textcoords="offset points")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("wall time [s] (median)")
    ax.set_ylabel("relative error (vs closed form / complex step)")
    ax.set_title("mbseig: error against wall time (labels: size)")
    ax.grid(True, which="both", alpha=0.3)
    if methods:
        ax.legend(fontsize=7, loc="center left", bbox_to_anchor=(1.01, 0.5))
    fig.tight_layout()
    return fig
