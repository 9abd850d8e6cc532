"""Plots of the time-domain check (matplotlib, imported only here and only when asked).

One PNG per simulated mode: the modal coordinate Re η(t) with the fitted envelope
|η̂₀| e^(−δ_m t) and the predicted envelope |η(0)| e^(−δ_p t), and below it the deviation of the
mode's dominant coordinate.  No pyplot state is touched (figures are rendered with the Agg canvas).
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from .errors import CaseError

__all__ = ["plot_check"]


def _slug(text):
    return re.sub(r"[^A-Za-z0-9_.-]+", "_", text).strip("_") or "case"


def plot_check(result, directory) -> list:
    """Write ``<case>_mode<k>.png`` per simulated mode of ``result`` into ``directory``."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

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
        fig = Figure(figsize=(8, 6), constrained_layout=True)
        FigureCanvasAgg(fig)
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
        path = out / f"{_slug(result.name)}_mode{m.index}.png"
        try:
            fig.savefig(path, dpi=110)
        except OSError as exc:
            raise CaseError(f"cannot write: {exc.strerror or exc}", file=str(path),
                            element="--plot") from None
        paths.append(path)
    return paths
