"""The report of a periodic case (DESIGN §8), on the page every motion shares
(:mod:`mbseig.report.page`), from what :func:`mbseig.studies.periodic_report.periodic_report_data`
computed.

Sections: the summary (verdict and its scope, the multiplier that decided it, its bound and
margin, the rule); the configuration: its model with parameters and units, the reference
motion, the modes (the Floquet multipliers with their error bounds and exponents, the figure of
the multipliers on the unit circle with their bounds beside the frozen-time eigenvalues, marked
as not a criterion), the time-domain check; then the studies (verdict over a parameter, located
boundaries, max|μ| against the parameter and, with lines, the stability chart).  Numbers follow
the zero rule (:mod:`mbseig.display`): a part of μ within its bound of 0 reads 0, an exponent
with the bound propagated from its multiplier's.  Output is deterministic: no timings, PNGs
without metadata, numbers at fixed precision.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ..display import fmt, fmt_complex, shown
from ..plots import save
from ..plots.common import styled
from ..plots.charts import chart_figure
from .provenance import provenance
from .page import head_blocks, page_blocks, write_page
from .sections import describe, parameter_blocks
from .summary import scope_sentences, verdict_cell
from .units import parameter_units

__all__ = ["periodic_blocks", "write_periodic_report", "multiplier_figure"]


@styled
def multiplier_figure(rep):
    """Left: the Floquet multipliers and the unit circle (|μ| = 1, the stability boundary).
    Right: the eigenvalues of the linearization frozen at instants of the period (grey) and the
    Floquet exponents (red), titled as not a criterion."""
    from matplotlib.figure import Figure

    fl = rep.floquet
    mu = np.array([complex(*m) for m in fl["multipliers"]])
    fig = Figure(figsize=(9, 4.2), layout="constrained")
    ax, bx = fig.subplots(1, 2)
    th = np.linspace(0, 2 * math.pi, 361)
    ax.plot(np.cos(th), np.sin(th), color="0.4", lw=1)
    colors = {"stable": "#2b8cbe", "critical": "#6a51a3", "unstable": "#de2d26"}
    for m, b in zip(mu, fl["error_bounds"], strict=True):
        st = "unstable" if abs(m) - b > 1 else "stable" if abs(m) + b < 1 else "critical"
        m = shown(m, b)
        ax.plot(m.real, m.imag, "o", color=colors[st], ms=7, mfc="none", mew=1.6)
        ax.plot(m.real + b * np.cos(th), m.imag + b * np.sin(th), color=colors[st], lw=0.8)
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
    bmax = max(fl["error_bounds"], default=0.0)
    ax.set_title(f"Floquet multipliers: {fl['verdict']}\n(circles of radius b, the error "
                 f"bound, ≤ {bmax:.1e}: true scale)", fontsize=8)
    ax.legend(fontsize=7, loc="lower left")
    lam = rep.frozen_eigenvalues.ravel()
    bx.plot(lam.real, lam.imag, ".", color="0.6", ms=3,
            label=f"frozen at {rep.frozen['instants']} instants")
    ex = np.array(fl["exponents"])
    bx.plot(ex[:, 0], ex[:, 1], "x", color="#de2d26", ms=7, mew=1.6, label="Floquet exponents")
    bx.axvline(0, color="0.4", lw=1)
    bx.margins(0.12)
    bx.set_xlabel("Re s [1/s]")
    bx.set_ylabel("Im s [rad/s]")
    bx.set_title(f"frozen-time eigenvalues: would say {rep.frozen['verdict']}\n"
                 "(not a stability criterion of a periodic motion)", fontsize=8)
    bx.legend(fontsize=7, loc="best")
    return fig


@styled
def _radius_figure(study):
    from matplotlib.figure import Figure

    fig = Figure(figsize=(6, 3.6), layout="constrained")
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
    return fig


def _multiplier_rows(fl, condition, ebounds):
    """One row a multiplier: μ (each part within its bound b of 0 reads 0), |μ|, b, κ, the
    exponent ln(μ)/T (parts within the propagated bound read 0), the stability."""
    rows = []
    for k, (m, ex, b) in enumerate(zip(fl["multipliers"], fl["exponents"], fl["error_bounds"],
                                       strict=True)):
        mod = abs(complex(*m))
        st = "unstable" if mod - b > 1 else "stable" if mod + b < 1 else "critical"
        eb = ebounds[k] if k < len(ebounds) else None
        rows.append([k + 1, fmt(m[0], b, "+.10f"), fmt(m[1], b, "+.10f"), f"{mod:.10f}",
                     f"{b:.1e}", f"{condition[k]:.3g}", fmt(ex[0], eb, "+.6g"),
                     fmt(ex[1], eb, "+.6g"), st])
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
    tag = rep.config or "base"
    d = fl["decided_by"]
    model = a.timed.base
    verdict = fl["verdict"]
    word = getattr(verdict, "word", verdict)
    mu = complex(*fl["multipliers"][d["index"]])
    decided = (f"multiplier {d['index'] + 1}: μ = {fmt_complex(mu, d['bound'], d['bound'])}, "
               f"|μ| = {d['modulus']:.10f} ± {d['bound']:.1e}, margin {d['margin']:.3g}")
    body = [("h2", "Summary"),
            ("table", ["configuration", "verdict", "deciding multiplier", "motion"],
             [[tag, verdict_cell(verdict), decided,
               f"periodic, period T = {fl['period']:.10g} s"]]),
            ("p", f"**Verdict: {word}** (Floquet multipliers of the periodic reference "
                  f"motion, period T = {fl['period']:.10g} s). Decided by multiplier "
                  f"{d['index'] + 1}: |μ| = {d['modulus']:.10f} ± {d['bound']:.1e}, margin "
                  f"{d['margin']:.3g}. Rule: stable when every |μ| + b < 1, unstable when some "
                  "|μ| − b > 1, critical otherwise; b is each multiplier's error bound, the "
                  "largest of the difference between two monodromy estimates (rtol "
                  f"{fl['tolerances'][0]:g} and {fl['tolerances'][1]:g}, the second on a shifted "
                  "sampling), the condition number times their difference, |μ| times the "
                  f"mismatch of Liouville's identity ({fl['det_check']:.1e}) and a rounding "
                  "floor.")]
    body += scope_sentences([(tag, verdict)])
    body += [("p", f"Frozen-time eigenvalues ({rep.frozen['instants']} instants): max Re s = "
                   f"{fmt(rep.frozen['max_real_part'], rep.frozen_bound, '.4g')}, which would say "
                   f"{rep.frozen['verdict']}. Not a stability criterion of a periodic motion; "
                   "shown for comparison only."),
             ("h2", f"Configuration {tag}"),
             ("p", f"**{tag}**: " + (describe(case, rep.config) if rep.config else
                                     "the case as written, no configuration applied") + "."),
             ("h3", "Model"),
             ("table", ["quantity", "value"], [
                 ["coordinates", str(model.n)], ["constraints", str(model.n_constraints)],
                 ["degrees of freedom", str(a.dof)], ["Floquet multipliers", str(2 * a.dof)],
                 ["monodromy", a.floquet.method]])]
    body += parameter_blocks(case, model, parameter_units(case))
    body += [("h3", "Reference motion"),
             ("p", f"Periodic with period T = {fl['period']:.10g} s. Reference: "
                   f"{fl['reference']['method']}, residual {fl['reference']['residual']:.2e} "
                   f"after {fl['reference']['iterations']} iterations. Time-dependent fields: "
                   + (", ".join(f"`{x}`" for x in fl["time_dependent"]) or "none") + ". "
                   f"Linearization sampled at {fl['samples']} instants (two samplings differ by "
                   f"{fl['sampling_difference']:.1e})."),
             ("h3", f"Modes — verdict: {word}"),
             ("p", "The modes of a periodic motion are its Floquet multipliers μ (eigenvalues of "
                   "the monodromy matrix over one period), with their exponents s = ln(μ)/T:"),
             ("table", ["#", "Re μ [–]", "Im μ [–]", "abs(μ) [–]", "bound b [–]", "κ [–]",
                        "Re s [1/s]", "Im s [rad/s]", "stability"],
              _multiplier_rows(fl, a.floquet.condition, rep.exponent_bounds)),
             ("p", "Exponents s = ln(μ)/T with Im s reduced into (−π/T, π/T]; κ is the "
                   "eigenvalue condition number of μ. A part of μ within its bound b of 0 is "
                   "printed as 0, a part of s within b/(|μ| T) of 0 likewise (the JSON keeps the "
                   "computed values).")]
    path = save(multiplier_figure(rep), out_dir / f"{stem}_multipliers.png")
    body.append(("img", path, "Floquet multipliers on the unit circle with their error bounds; "
                              "right: frozen-time eigenvalues (not a criterion) and the Floquet "
                              "exponents"))
    inst = np.linspace(0, rep.frozen_times.size, 8, endpoint=False).astype(int)
    fb = rep.frozen_bound
    rows = [[f"{rep.frozen_times[i]:.6g}", fmt(rep.frozen_eigenvalues[i].real.max(), fb, "+.6g"),
             ", ".join(fmt_complex(s, fb, fb, ".4g") for s in rep.frozen_eigenvalues[i]
                       if s.imag >= 0)] for i in inst]
    body += [("p", "**Frozen-time eigenvalues (not a criterion)**, at 8 of the instants:"),
             ("table", ["t [s]", "max Re s [1/s]", "eigenvalues (Im ≥ 0) [1/s]"], rows)]
    body.append(("h3", "Time-domain check"))
    if rep.check is not None:
        c = rep.check
        body.append(("p", f"The nonlinear model started from the reference perturbed along the "
                          f"Floquet vector of multiplier {c.index + 1} (amplitude "
                          f"{c.amplitude:.3g}) grows by {c.growth:.10g} per period over "
                          f"{c.periods} periods against |μ| = {c.modulus:.10g}: relative error "
                          f"{c.relative_error:.2e}, tolerance {c.rtol:g}: "
                          f"**{'passed' if c.passed else 'FAILED'}**."))
    else:
        body.append(("p", "Time-domain check not run (report built with --no-check)."))
    for k, st in enumerate(rep.studies, 1):
        body += _study_blocks(st, out_dir, stem, k)
    head = head_blocks(stem, rep.description, provenance(case), [rep.config], motion="periodic")
    return page_blocks(head, body)


def write_periodic_report(rep, case, out_dir):
    """Write report.md and report.html of a periodic case; returns their paths."""
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    return write_page(periodic_blocks(rep, case, out_dir), out_dir,
                      f"Stability report: {rep.name}")
