"""Figures of ``mbseig uncertainty``: the histogram of the least damping with δ = 0 marked, and
for two inputs the samples coloured by verdict with the stability boundary."""

from __future__ import annotations

import numpy as np

from .common import figure, styled

__all__ = ["damping_histogram", "verdict_scatter", "shown_damping"]

#: colours of the verdicts (stable, critical, unstable, failed)
COLOURS = {"stable": "tab:green", "critical": "tab:orange", "unstable": "tab:red",
           "failed": "0.4"}
WORDS = ("stable", "critical", "unstable", "failed")


def shown_damping(delta, bound):
    """δ as a person reads it: 0 where it is within its error bound of 0 (DESIGN §6)."""
    delta = np.asarray(delta, float)
    bound = np.asarray(bound, float)
    return np.where(np.abs(delta) <= bound, 0.0, delta)


@styled
def damping_histogram(delta, bound, code, *, case="", method="", unit="1/s"):
    """Histogram of the least damping of the evaluated samples (failed ones left out, counted
    in the title), δ = 0 marked."""
    d = shown_damping(delta, bound)
    ok = np.isfinite(d) & (np.asarray(code) != 3)
    fig = figure(figsize=(6.0, 3.6), layout="constrained")
    ax = fig.add_subplot()
    vals = d[ok]
    if vals.size:
        lo, hi = float(vals.min()), float(vals.max())
        if lo == hi:
            lo, hi = lo - 0.5 * max(abs(lo), 1.0), hi + 0.5 * max(abs(hi), 1.0)
        edges = np.linspace(lo, hi, 41)
        for word, k in (("stable", 0), ("critical", 1), ("unstable", 2)):
            sel = ok & (np.asarray(code) == k)
            if sel.any():
                ax.hist(d[sel], bins=edges, color=COLOURS[word], alpha=0.8,
                        label=f"{word} ({int(sel.sum())})")
        ax.legend(loc="best")
    ax.axvline(0.0, color="k", lw=1.0, ls="--")
    ax.text(0.0, 1.0, " δ = 0", transform=ax.get_xaxis_transform(), va="top", ha="left")
    failed = int((~ok).sum())
    ax.set_xlabel(f"least damping δ ({unit})")
    ax.set_ylabel("samples")
    ax.set_title(f"{case}\nleast damping of {int(ok.sum())} samples"
                 + (f" ({failed} failed)" if failed else "") + (f", {method}" if method else ""))
    return fig


@styled
def verdict_scatter(x, code, names, *, grid=None, case="", units=("", "")):
    """The samples of two inputs coloured by verdict; ``grid`` = (g1, g2, δ) the least damping
    on a grid (δ shown as 0 within its bound, NaN where it failed), whose δ = 0 contour is
    drawn as the stability boundary."""
    x = np.asarray(x, float)
    code = np.asarray(code)
    fig = figure(figsize=(5.6, 4.6), layout="constrained")
    ax = fig.add_subplot()
    for k, word in enumerate(WORDS):
        sel = code == k
        if sel.any():
            ax.scatter(x[sel, 0], x[sel, 1], s=4 if sel.sum() > 2000 else 9, c=COLOURS[word],
                       label=f"{word} ({int(sel.sum())})", linewidths=0,
                       alpha=0.6 if sel.sum() > 2000 else 0.9)
    if grid is not None:
        g1, g2, D = grid
        D = np.asarray(D, float)
        if np.isfinite(D).sum() >= 4 and np.nanmin(D) < 0 < np.nanmax(D):
            cs = ax.contour(g1, g2, D.T, levels=[0.0], colors="k", linewidths=1.5)
            ax.plot([], [], "k-", lw=1.5, label="boundary δ = 0")
            del cs
    ax.legend(loc="best", fontsize=8)
    lab = [f"{n}" + (f" ({u})" if u else "") for n, u in zip(names, units, strict=True)]
    ax.set_xlabel(lab[0])
    ax.set_ylabel(lab[1])
    ax.set_title(f"{case}\nverdict of each sample")
    return fig
