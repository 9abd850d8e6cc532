"""The report of a periodic case (DESIGN §8): ``report.md`` and a self-contained
``report.html`` (rendered by :mod:`mbseig.report.render`), from what
:func:`mbseig.studies.periodic_report.periodic_report_data` computed.

Sections: the summary (verdict, the multiplier that decided it, its bound and margin, the
tolerances); the reference motion; the Floquet multipliers with their error bounds and
exponents; the figure of the multipliers on the unit circle beside the frozen-time eigenvalues
(marked as not a criterion); the time-domain check; the studies (verdict over a parameter,
located boundaries, max|μ| against the parameter and, with lines, the stability chart).
Output is deterministic: no timings, PNGs without metadata, numbers at fixed precision.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ..plots import save
from ..plots.common import styled
from ..studies.floquet_sweep import chart_figure
from .build import provenance
from .render import render_html, render_markdown

__all__ = ["periodic_blocks", "write_periodic_report", "multiplier_figure"]


@styled
def multiplier_figure(rep):
    """Left: the Floquet multipliers and the unit circle (|μ| = 1, the stability boundary).
    Right: the eigenvalues of the linearization frozen at instants of the period (grey) and the
    Floquet exponents (red), titled as not a criterion."""
    from matplotlib.figure import Figure

    fl = rep.floquet
    mu = np.array([complex(*m) for m in fl["multipliers"]])
    fig = Figure(figsize=(9, 4.2))
    ax, bx = fig.subplots(1, 2)
    th = np.linspace(0, 2 * math.pi, 361)
    ax.plot(np.cos(th), np.sin(th), color="0.4", lw=1)
    colors = {"stable": "#2b8cbe", "critical": "#6a51a3", "unstable": "#de2d26"}
    for m, b in zip(mu, fl["error_bounds"]):
        st = "unstable" if abs(m) - b > 1 else "stable" if abs(m) + b < 1 else "critical"
        ax.plot(m.real, m.imag, "o", color=colors[st], ms=7, mfc="none", mew=1.6)
    for st, c in colors.items():
        ax.plot([], [], "o", color=c, mfc="none", mew=1.6, label=st)
    lim = max(1.25, 1.1 * float(np.max(np.abs(mu), initial=1.0)))
    ax.set_xlim(-lim, lim)
    ax.set_ylim(-lim, lim)
    ax.set_aspect("equal")
    ax.axhline(0, color="0.85", lw=0.8)
    ax.axvline(0, color="0.85", lw=0.8)
    ax.set_xlabel("Re μ")
    ax.set_ylabel("Im μ")
    ax.set_title(f"Floquet multipliers: {fl['verdict']}")
    ax.legend(fontsize=7, loc="lower left")
    lam = rep.frozen_eigenvalues.ravel()
    bx.plot(lam.real, lam.imag, ".", color="0.6", ms=3,
            label=f"frozen at {rep.frozen['instants']} instants")
    ex = np.array(fl["exponents"])
    bx.plot(ex[:, 0], ex[:, 1], "x", color="#de2d26", ms=7, mew=1.6, label="Floquet exponents")
    bx.axvline(0, color="0.4", lw=1)
    bx.set_xlabel("Re s [1/s]")
    bx.set_ylabel("Im s [rad/s]")
    bx.set_title(f"frozen-time eigenvalues: would say {rep.frozen['verdict']}\n"
                 "(not a stability criterion of a periodic motion)", fontsize=8)
    bx.legend(fontsize=7, loc="best")
    fig.tight_layout()
    return fig


@styled
def _radius_figure(study):
    from matplotlib.figure import Figure

    fig = Figure(figsize=(6, 3.6))
    ax = fig.add_subplot()
    for k, sw in enumerate(study.sweeps):
        label = (f"{study.line_parameter} = {study.line_values[k]:g}" if study.line_parameter
                 else None)
        ax.plot(sw.values, [r.spectral_radius for r in sw.results], "o-", ms=3, label=label)
        for b in sw.boundaries:
            ax.axvline(b.value, color="0.6", lw=0.8, ls="--")
    ax.axhline(1.0, color="k", lw=0.8)
    ax.set_xlabel(study.parameter)
    ax.set_ylabel("max |μ|")
    ax.set_title("spectral radius of the monodromy matrix (dashed: verdict changes)", fontsize=8)
    if study.line_parameter:
        ax.legend(fontsize=7)
    fig.tight_layout()
    return fig


def _multiplier_rows(fl, condition):
    rows = []
    for k, (m, ex, b) in enumerate(zip(fl["multipliers"], fl["exponents"], fl["error_bounds"])):
        mod = abs(complex(*m))
        st = "unstable" if mod - b > 1 else "stable" if mod + b < 1 else "critical"
        rows.append([k + 1, f"{m[0]:+.10f}", f"{m[1]:+.10f}", f"{mod:.10f}", f"{b:.1e}",
                     f"{condition[k]:.3g}", f"{ex[0]:+.6g}", f"{ex[1]:+.6g}", st])
    return rows


def _study_blocks(study, out_dir, stem, index):
    blocks = [("h2", f"Study: {study.title}")]
    if study.kind != "sweep":
        return blocks + [("p", study.note)]
    name = study.parameter
    tol = study.sweeps[0].rel_tol
    blocks.append(("p", f"Floquet verdict over {name} ({len(study.sweeps[0].values)} points"
                        + (f", one line per {study.line_parameter}" if study.line_parameter else "")
                        + f"); boundaries located to {tol:g} relative (Brent's method on "
                          "det(I + Φ), det(Φ − I) or max|μ| − 1, else bisection of the verdict)."))
    rows = []
    for k, sw in enumerate(study.sweeps):
        line = f"{study.line_parameter} = {study.line_values[k]:g}" if study.line_parameter else "–"
        for b in sw.boundaries:
            rows.append([line, f"{b.value:.12g}", b.kind, b.stability,
                         f"{b.verdicts[0]} → {b.verdicts[1]}", b.method])
        if not sw.boundaries:
            rows.append([line, "–", "–", "–", f"{sw.results[0].verdict} over the range", "–"])
    blocks.append(("table", ["line", name, "kind", "stability", "verdicts", "located by"], rows))
    path = save(_radius_figure(study), out_dir / f"{stem}_study{index}_radius.png")
    blocks.append(("img", path, f"max|μ| against {name}"))
    if study.chart is not None:
        fig = chart_figure(study.chart)
        fig.axes[0].set_title(f"stability chart over ({name}, {study.line_parameter})")
        path = save(fig, out_dir / f"{stem}_study{index}_chart.png")
        blocks.append(("img", path, f"stability chart over {name} and {study.line_parameter} "
                                    "(red unstable, blue critical, white stable)"))
    return blocks


def periodic_blocks(rep, case, out_dir):
    """The report's blocks (:mod:`mbseig.report.render`); figures are written to ``out_dir``."""
    out_dir = Path(out_dir)
    fl, a = rep.floquet, rep.analysis
    stem = rep.name
    prov = provenance(case)
    d = fl["decided_by"]
    model = a.timed.base
    body = [("h2", "Summary"),
            ("p", f"**Verdict: {fl['verdict']}** (Floquet multipliers of the periodic reference "
                  f"motion, period T = {fl['period']:.10g} s). Decided by multiplier "
                  f"{d['index'] + 1}: |μ| = {d['modulus']:.10f} ± {d['bound']:.1e}, margin "
                  f"{d['margin']:.3g}. Rule: stable when every |μ| + b < 1, unstable when some "
                  "|μ| − b > 1, critical otherwise; b is each multiplier's error bound, the "
                  "largest of the difference between two monodromy estimates (rtol "
                  f"{fl['tolerances'][0]:g} and {fl['tolerances'][1]:g}, the second on a shifted "
                  "sampling), the condition number times their difference, |μ| times the "
                  f"mismatch of Liouville's identity ({fl['det_check']:.1e}) and a rounding floor."),
            ("p", f"Frozen-time eigenvalues ({rep.frozen['instants']} instants): max Re s = "
                  f"{rep.frozen['max_real_part']:.4g}, which would say {rep.frozen['verdict']}. "
                  "Not a stability criterion of a periodic motion; shown for comparison only."),
            ("h2", "Reference motion"),
            ("p", f"{model.n} coordinates, {model.n_constraints} constraints, {a.dof} degrees of "
                  f"freedom: {2 * a.dof} multipliers. Reference: {fl['reference']['method']}, "
                  f"residual {fl['reference']['residual']:.2e} after "
                  f"{fl['reference']['iterations']} iterations. Time-dependent fields: "
                  + (", ".join(f"`{x}`" for x in fl["time_dependent"]) or "none") + ". "
                  f"Linearization sampled at {fl['samples']} instants (two samplings differ by "
                  f"{fl['sampling_difference']:.1e}); {a.floquet.method}."),
            ("h2", "Floquet multipliers"),
            ("table", ["#", "Re μ", "Im μ", "abs(μ)", "bound", "κ", "Re s [1/s]", "Im s [rad/s]",
                       "stability"], _multiplier_rows(fl, a.floquet.condition)),
            ("p", "Exponents s = ln(μ)/T with Im s reduced into (−π/T, π/T]; κ is the "
                  "eigenvalue condition number of μ.")]
    path = save(multiplier_figure(rep), out_dir / f"{stem}_multipliers.png")
    body.append(("img", path, "Floquet multipliers on the unit circle; right: frozen-time "
                              "eigenvalues (not a criterion) and the Floquet exponents"))
    inst = np.linspace(0, rep.frozen_times.size, 8, endpoint=False).astype(int)
    rows = [[f"{rep.frozen_times[i]:.6g}", f"{rep.frozen_eigenvalues[i].real.max() + 0.0:+.6g}",
             ", ".join(f"{s.real + 0.0:+.4g}{s.imag + 0.0:+.4g}j" for s in rep.frozen_eigenvalues[i]
                       if s.imag >= 0)] for i in inst]
    body += [("h3", "Frozen-time eigenvalues (not a criterion)"),
             ("table", ["t [s]", "max Re s", "eigenvalues (Im ≥ 0)"], rows)]
    if rep.check is not None:
        c = rep.check
        body += [("h2", "Time-domain check"),
                 ("p", f"The nonlinear model started from the reference perturbed along the "
                       f"Floquet vector of multiplier {c.index + 1} (amplitude {c.amplitude:.3g}) "
                       f"grows by {c.growth:.10g} per period over {c.periods} periods against "
                       f"|μ| = {c.modulus:.10g}: relative error {c.relative_error:.2e}, tolerance "
                       f"{c.rtol:g}: **{'passed' if c.passed else 'FAILED'}**.")]
    for k, st in enumerate(rep.studies, 1):
        body += _study_blocks(st, out_dir, stem, k)
    head = [("h1", f"Stability report: {stem} (periodic motion)"),
            ("p", rep.description),
            ("p", f"Generated by mbseig {prov['mbseig']} on {prov['date']} (UTC) from "
                  f"`{prov['case']}` (SHA-256 {prov['sha256'][:16]}…; numpy {prov['numpy']}, "
                  f"scipy {prov['scipy']}). Configuration: {rep.config or 'base'}. Regenerate "
                  f"with `mbseig report cases/{prov['case']}`.")]
    toc = [("h2", "Contents"), ("toc", [(int(b[0][1]), b[1]) for b in body
                                         if b[0] in ("h2", "h3")])]
    return head + toc + body


def write_periodic_report(rep, case, out_dir):
    """Write report.md and report.html of a periodic case; returns their paths."""
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    blocks = periodic_blocks(rep, case, out_dir)
    md, page = out_dir / "report.md", out_dir / "report.html"
    md.write_text(render_markdown(blocks, out_dir))
    page.write_text(render_html(blocks, f"Stability report: {rep.name}"))
    return md, page
