"""Figures of a report's first page: the least-damped pole of every configuration with the
boundaries found, on one ζ/ω_n grid, and the tornado chart of the parameters that move the
least-damped mode.  Inputs are plain lists of dicts (the report passes what
:mod:`mbseig.studies.report_studies` computed); nothing here computes a result."""

from __future__ import annotations

import numpy as np

from .common import colormap, figure, styled
from .poles import zeta_wn_grid

__all__ = ["summary_poles", "tornado"]


@styled
def summary_poles(poles, boundaries, *, title="least-damped mode of every configuration"):
    """``poles``: [{"label", "s" (complex), "stable" (bool)}] drawn as filled circles (hollow when
    not stable) with their conjugates; ``boundaries``: [{"label", "s"}] the eigenvalue of the
    crossing mode at each boundary found (on the imaginary axis), drawn as crosses.  Lines of
    constant ζ and circles of constant ω_n under them; legend outside the axes."""
    fig = figure(layout="constrained", figsize=(8.2, 4.8))
    ax = fig.subplots()
    s_all = [complex(p["s"]) for p in poles] + [complex(b["s"]) for b in boundaries]
    radius = max((abs(s) for s in s_all), default=0.0) * 1.12 or 1.0
    zeta_wn_grid(ax, radius)
    cmap = colormap("tab10")
    for k, p in enumerate(poles):
        s, c = complex(p["s"]), cmap(k % 10)
        ax.plot([s.real, s.real], [s.imag, -s.imag], "o", color=c, ms=7,
                mfc=c if p.get("stable", True) else "none", mew=1.4, ls="none",
                label=p["label"], zorder=3)
    for b in boundaries:
        s = complex(b["s"])
        ax.plot([s.real, s.real], [s.imag, -s.imag], "x", color="k", ms=8, mew=1.5, ls="none",
                zorder=4)
        ax.annotate(b["label"], (s.real, abs(s.imag)), textcoords="offset points",
                    xytext=(6, 2), fontsize=7, zorder=5)
    if boundaries:
        ax.plot([], [], "x", color="k", ms=7, mew=1.5, ls="none",
                label="boundary found (critical value)")
    ax.axvline(0.0, color="k", lw=0.8)
    ax.axhline(0.0, color="k", lw=0.3)
    re_max = max((s.real for s in s_all), default=0.0)
    ax.set_xlim(-radius, max(0.5 * radius, 1.1 * re_max))  # room for the labels
    ax.set_ylim(-radius, radius)
    ax.set_xlabel("Re s = −δ [1/s]")
    ax.set_ylabel("Im s = ±ω_d [rad/s]")
    ax.set_title(title)
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.02, 1.0), borderaxespad=0.0,
              title="filled: stable", title_fontsize=7)
    return fig


@styled
def tornado(panels, *, change_pct=10.0):
    """One panel a configuration: ``panels`` = [{"title", "rows": [(parameter label, change of
    δ per +1 % of the parameter [1/s])]}], largest first.  Each bar is the first-order change of
    the damping δ = −Re s for ∓``change_pct`` % (light) and ±``change_pct`` % (dark) of the
    parameter: right of 0 damps the mode, left of 0 takes damping away."""
    n = max(len(panels), 1)
    cols = min(n, 3)
    grid_rows = -(-n // cols)
    bars = max((len(p["rows"]) for p in panels), default=1) or 1
    fig = figure(layout="constrained", figsize=(4.6 * cols if cols > 1 else 6.0,
                          grid_rows * (0.38 * bars + 1.3) + 0.5))
    axes = list(np.ravel(fig.subplots(grid_rows, cols, squeeze=False)))
    for ax in axes[len(panels):]:
        ax.axis("off")
    for ax, p in zip(axes, panels, strict=False):  # the grid's spare axes are switched off
        labels = [r[0] for r in p["rows"]][::-1]
        up = np.array([r[1] * change_pct for r in p["rows"]][::-1], float)
        y = np.arange(len(labels))
        ax.barh(y, up, color=np.where(up >= 0, "tab:blue", "tab:red"), height=0.6)
        ax.barh(y, -up, color=np.where(up >= 0, "tab:red", "tab:blue"), height=0.6, alpha=0.35)
        ax.axvline(0.0, color="k", lw=0.8)
        ax.set_yticks(y)
        ax.set_yticklabels(labels, fontsize=7)
        lim = float(np.max(np.abs(up), initial=0.0)) * 1.15 or 1.0
        ax.set_xlim(-lim, lim)
        ax.set_xlabel(f"change of δ = −Re s for ±{change_pct:g} % [1/s]", fontsize=7)
        ax.set_title(p["title"], fontsize=8)
        ax.grid(True, axis="x", lw=0.3)
    from matplotlib.patches import Patch

    fig.legend(handles=[Patch(color="0.3", label=f"+{change_pct:g} % of the parameter"),
                        Patch(color="0.3", alpha=0.35, label=f"−{change_pct:g} %"),
                        Patch(color="tab:blue", label="adds damping"),
                        Patch(color="tab:red", label="takes damping away")],
               loc="outside lower center", ncol=4, fontsize=7, frameon=False)
    return fig
