"""Figures for sweeps and reports (matplotlib, imported lazily; PNG without timestamps).

Every function writes one PNG and returns its path; output is byte-identical for identical
inputs (Agg backend, fixed size and dpi, no date or software metadata).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

__all__ = ["root_locus", "modes_vs_parameter", "stability_map", "pole_map", "mechanism_modes",
           "save"]

DPI = 100


def _plt():
    import matplotlib

    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as plt

    plt.rcParams.update({"svg.hashsalt": "mbseig", "font.size": 9})
    return plt


def save(fig, path):
    path = Path(path)
    fig.savefig(path, dpi=DPI, metadata={"Software": None})
    import matplotlib.pyplot as plt

    plt.close(fig)
    return path


def _listed(S):
    from .sweep import _listed_tracks

    return _listed_tracks(S)


def root_locus(res, path):
    """Tracked eigenvalues in the s-plane, coloured by track, along the first axis (all lines)."""
    plt = _plt()
    fig, ax = plt.subplots(figsize=(7, 5))
    cmap = plt.get_cmap("tab10")
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
    return save(fig, path)


def modes_vs_parameter(res, path):
    """Frequency ω/2π and damping δ of each listed track against the first axis."""
    plt = _plt()
    fig, (a1, a2) = plt.subplots(2, 1, figsize=(7, 6), sharex=True)
    cmap = plt.get_cmap("tab10")
    x = res.values
    for l, S in enumerate(res.tracks):
        for j in _listed(S):
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
    return save(fig, path)


def stability_map(res, path):
    """Two-parameter map: spectral abscissa max Re s (colour), the α = 0 contour and the located
    boundaries (points)."""
    plt = _plt()
    fig, ax = plt.subplots(figsize=(7, 5))
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
    ax.set_xlabel(res.axes[0][0])
    ax.set_ylabel(res.axes[1][0])
    ax.set_title("stability map: black line α = 0, dots = boundaries located by root finding")
    fig.tight_layout()
    return save(fig, path)


def pole_map(eigenvalues, path, *, title="pole map", stability=None):
    """Eigenvalues (both halves of each pair) in the s-plane."""
    plt = _plt()
    fig, ax = plt.subplots(figsize=(6, 4.5))
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
    return save(fig, path)


def mechanism_modes(model, q0, shapes, labels, path, *, amplitude=0.15, title=""):
    """The mechanism at equilibrium (black) with each mode shape superposed (one panel a mode).

    A mode shape (complex, full coordinates) is drawn at the phase of its largest component:
    q = q0 ± a·L·Re(e^{-iφ} v)/max|v| with a = ``amplitude`` and L the model's size.
    """
    plt = _plt()
    n = len(labels)
    cols = min(n, 3) or 1
    rows = max(1, math.ceil(n / cols))
    fig, axes = plt.subplots(rows, cols, figsize=(4.2 * cols, 3.8 * rows), squeeze=False)
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
    return save(fig, path)
