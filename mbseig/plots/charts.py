"""The Floquet stability chart over two parameters (the Ince–Strutt chart of a Mathieu-type
system), drawn from :class:`mbseig.studies.floquet_sweep.StabilityChart`."""

from __future__ import annotations

import numpy as np

__all__ = ["chart_figure"]


def chart_figure(chart, *, ax=None):
    """A matplotlib Figure of the chart: the first parameter across, the second up; unstable
    shaded red, critical blue, stable white, and the spectral radius max|μ| written in each
    unstable cell.  Uses matplotlib.figure.Figure, so the backend is never switched."""
    from matplotlib.colors import ListedColormap
    from matplotlib.figure import Figure
    from matplotlib.patches import Patch

    code = np.vectorize({"stable": 0, "critical": 1, "unstable": 2}.get)(chart.verdicts)
    if ax is None:
        fig = Figure(figsize=(7, 4.5))
        ax = fig.add_subplot()
        fig.subplots_adjust(right=0.8)
    else:
        fig = ax.figure
    colors = ["white", "#9ecae1", "#de2d26"]
    ax.pcolormesh(chart.p1, chart.p2, code.astype(float).T, cmap=ListedColormap(colors),
                  vmin=0, vmax=2, shading="nearest", edgecolors="#dddddd", linewidth=0.3)
    if code.size <= 400:
        for i, a in enumerate(chart.p1):
            for j, b in enumerate(chart.p2):
                if code[i, j] == 2:
                    ax.text(a, b, f"{chart.spectral_radius[i, j]:.2f}", ha="center",
                            va="center", fontsize=6, color="white")
    ax.set_xlabel(chart.names[0])
    ax.set_ylabel(chart.names[1])
    ax.legend(handles=[Patch(facecolor=c, edgecolor="#888888", label=v)
                       for c, v in zip(colors, ("stable", "critical", "unstable"), strict=True)],
              loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=7)
    ax.set_title("Floquet stability chart (numbers: max|μ| where unstable)")
    return fig
