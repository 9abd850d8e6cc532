"""Stability reports: ``report.md`` and a self-contained ``report.html`` per case.

For each configuration (all of the case's ``[configurations]`` with ``all_configs``): the model
summary, the equilibrium (posture, range-of-motion flags, pin reactions, constraint forces,
actuator effort), the mode table with verdict and margins, the mechanism at equilibrium with
each mode shape superposed, the pole map and the time-domain check of every mode
(:mod:`mbseig.check`).  Then the studies declared in ``[[report.studies]]``:

- ``sweep``: a parameter swept over ``range`` with ``count`` points on ``config`` (optionally
  one line per value of ``lines = {name = [values]}``); its stability boundaries
  (:func:`mbseig.studies.run_sweep`) and the parameter value at which the equilibrium leaves the
  range of motion (Brent's method on the smallest joint margin, same ``xtol``).
- ``compare = "constraint_stiffness"``: the eigenvalues of ``config`` with and without the
  constraint-force stiffness Σ λ ∇²Φ.

Output is deterministic: no dates or timings; figures are PNGs without metadata; numbers are
formatted at fixed precision.  The HTML embeds every figure as a base64 data URI; the PNGs are
also written next to report.md, which links them.
"""

from __future__ import annotations

import hashlib
import math
import os
import time
from pathlib import Path

import numpy as np

from .. import plots
from ..check import check_modes
from ..errors import MbseigError
from ..linear import linearize
from ..modal import modes
from ..model.linear_case import LinearCase
from ..numerics import user_names
from ..statics import equilibrium
from ..statics.reactions import posture, reactions
from ..studies import analyze, run_sweep, write_outputs
from ..studies.point import as_spec
from .render import render_html, render_markdown
from .units import parameter_units, with_unit

__all__ = ["build_report", "write_report"]


# ---------------------------------------------------------------------------------------------
# blocks: ("h1"|"h2"|"h3"|"p"|"pre", text) | ("table", header, rows) | ("img", path, caption)
def _fmt(x, digits=6):
    if x is None:
        return "–"
    if isinstance(x, str):
        return x
    if isinstance(x, (bool, np.bool_)):
        return "yes" if x else "no"
    x = float(x)
    if not math.isfinite(x):
        return "–"
    if x == 0:
        return "0"
    return f"{x:.{digits}g}"


def _config_blocks(case, config, out_dir, *, run_check, stem, units):
    a = analyze(case, config=config)
    model, eq, lin, md = a.model, a.eq, a.linear, a.modes
    tag = config or "base"
    blocks = [("h2", f"Configuration {tag}")]
    blocks.append(("p", f"**{tag}**: " + (_describe(case, config) if config else
                                          "the case as written, no configuration applied") + "."))
    blocks.append(("h3", "Model"))
    blocks.append(("table", ["quantity", "value"], [
        ["coordinates", str(model.n)],
        ["constraints", str(model.n_constraints)],
        ["redundant constraints", f"{eq.n_redundant}" + (f" ({'; '.join(eq.redundant)})" if eq.redundant else "")],
        ["degrees of freedom", str(lin.dof)],
        ["equilibrium residual", f"{eq.residual:.1e} ({eq.iterations} Newton iterations)"],
        ["eigensolver", f"{md.solver} ({md.solver_reason})"],
    ]))
    raw = getattr(case, "parameters", {}) or {}
    prow, derived = [], []
    for k, v in model.parameters.items():
        u = units.get(k)
        unit = "–" if u == "1" else (u or "not given in the case")
        if isinstance(raw.get(k), str):
            derived.append(f"{k} = {with_unit(_fmt(v, 6), u) if u else _fmt(v, 6)} "
                           f"(`{raw[k]}`" + ("" if u else ", unit not given in the case") + ")")
        else:
            prow.append([k, _fmt(v, 6), unit])
    if prow:
        blocks.append(("table", ["parameter", "value", "unit"], prow))
    if derived:
        blocks.append(("p", "Derived parameters: " + "; ".join(derived) + "."))
    linear_case = isinstance(model, LinearCase)  # matrices only: no posture, reactions or drawing
    rep = (dict(posture=[], out_of_range=[], drivers=[], actuator=[], pins=[], constraints=[])
           if linear_case else reactions(model, eq))
    if not linear_case:
        blocks.append(("h3", "Equilibrium"))
        blocks.append(("p", _statics_text(eq)))
    if rep["posture"]:
        blocks.append(("table", ["joint", "flexion [deg]", "range [deg]", "margin [deg]", "in range"],
                       [[p["name"], _fmt(p["angle_deg"], 6),
                         "–" if p["range_deg"] is None else f"{p['range_deg'][0]:g} … {p['range_deg'][1]:g}",
                         _fmt(p["margin_deg"], 4), "yes" if p["in_range"] else "**NO**"]
                        for p in rep["posture"]]))
        flags = rep["out_of_range"]
        blocks.append(("p", "Range of motion: " + ("all joints inside." if not flags else
                                                    "OUTSIDE for " + ", ".join(flags) + ".")))
    for d in rep["drivers"]:
        sets = "; ".join(
            f"{s['element']}: " + (f"free length {s['free_length'] * 1e3:.6g} mm, length "
                                   f"{s['length'] * 1e3:.6g} mm, tension {s['tension']:.6g} N"
                                   if "free_length" in s else f"locked at {s['length'] * 1e3:.6g} mm")
            for s in d["sets"])
        unloaded = d.get("unloaded") or []
        held = (f" The command is set on the device without {', '.join(unloaded)} and held as "
                f"that load changes (a position command)." if unloaded else "")
        blocks.append(("p", f"Inverse statics ({d['driver']}): commanded angle "
                            f"{math.degrees(d['angle_target']):.6g} deg needs an effort of "
                            f"{d['effort']:.6g} {d['effort_unit']}; {sets}.{held}"))
    if rep["actuator"]:
        blocks.append(("table", ["actuator element", "kind", "length [mm]", "tension [N]"],
                       [[r["element"], r["kind"], _fmt(r["length"] * 1e3, 6), _fmt(r["tension"], 6)]
                        for r in rep["actuator"]]))
    if rep["pins"]:
        blocks.append(("table", ["pin (force on the outboard bodies)", "point", "Fx [N]", "Fy [N]", "|F| [N]"],
                       [[p["name"], p["point"], _fmt(p["force"][0], 5), _fmt(p["force"][1], 5),
                         _fmt(p["magnitude"], 5)] for p in rep["pins"]]))
    rows = []
    for c in rep["constraints"]:
        r = c["reaction"]
        value = r["value"] if isinstance(r["value"], list) else [r["value"]]
        carried = f"{r['label']} {', '.join(_fmt(x, 5) for x in value)} {r['unit']}".rstrip()
        rows.append([c["element"], ", ".join(_fmt(x, 6) for x in c["multipliers"]), carried])
    if rows:
        blocks.append(("table", ["constraint", "multiplier λ (in the constraint's own scaling)",
                                 "reaction"], rows))

    blocks.append(("h3", f"Modes — verdict: {md.verdict}"))
    rows = []
    for k in range(len(md)):
        s = md.eigenvalues[k]
        margin = md.delta[k] - md.tolerance[k]
        rows.append([str(k + 1), f"{s.real:.6g}", f"{s.imag:.6g}",
                     _fmt(md.omega_n[k] / (2 * math.pi), 6), _fmt(abs(s.imag) / (2 * math.pi), 6),
                     _fmt(md.zeta[k], 4), _fmt(md.delta[k], 5), f"{margin:.4g}", md.stability[k],
                     md.kind[k], ", ".join(n for n, _ in md.dominant[k][:3])])
    blocks.append(("table", ["mode", "Re s [1/s]", "Im s [rad/s]", "ω_n/2π [Hz] (undamped)",
                             "ω_d/2π [Hz] (damped)", "ζ [–]", "δ [1/s]", "margin δ − tol [1/s]",
                             "stability", "kind", "dominant coordinates"], rows))
    least = int(np.argmin(md.delta)) if len(md) else None
    min_margin = float(np.min(md.delta - md.tolerance)) if len(md) else math.nan
    if least is not None:
        blocks.append(("p", f"Stability margin: the least-damped mode is mode {least + 1} with "
                            f"δ = {float(md.delta[least]):.5g} 1/s (ζ = {float(md.zeta[least]):.4g}); "
                            f"δ − tol = {min_margin:.4g} 1/s (tol per mode: max(10 κ η, 1e-12 |s|))."))
    labels = [_mode_label(k, md) for k in range(len(md))]
    if not linear_case:
        if model.dimension == 3:
            fig = _spatial_draw()(model, eq.q, md.shapes, labels,
                                  title=f"{tag}: equilibrium (black) and mode shapes (±, red/blue)")
        else:
            fig = plots.mechanism_modes(
                eq.model if eq.model is not None else model, eq.q, md.shapes, labels,
                eigenvalues=md.eigenvalues, kinds=list(md.kind),
                title=f"{tag}: equilibrium (black) and mode shapes, rigid bodies kept rigid")
        img = plots.save(fig, out_dir / f"{stem}_{tag}_shapes.png")
        blocks.append(("img", img, f"{tag}: mechanism at equilibrium with every element (bodies, "
                                   f"springs, sliders and their guides, torsional springs, loads) "
                                   f"and each mode shape superposed: displaced along the mode and "
                                   f"projected back onto the constraints Φ(q) = 0, so bodies stay "
                                   f"rigid; a real (overdamped) mode is drawn as its decay"))
    img = plots.save(plots.pole_map(md.eigenvalues, title=f"{tag}: pole map",
                                    stability=md.stability), out_dir / f"{stem}_{tag}_poles.png")
    blocks.append(("img", img, f"{tag}: pole map over lines of constant ζ and circles of constant "
                               f"ω_n; numbers are the modes of the table"))
    blocks += _check_blocks(a, run_check)
    summary = {"config": tag, "dof": lin.dof, "verdict": md.verdict, "least": least,
               "least_mode": None if least is None else {
                   "mode": least + 1, "delta": float(md.delta[least]),
                   "zeta": float(md.zeta[least]), "kind": md.kind[least],
                   "fn": float(md.omega_n[least] / (2 * math.pi)),
                   "fd": float(abs(md.eigenvalues[least].imag) / (2 * math.pi)),
                   "margin": float(md.delta[least] - md.tolerance[least])},
               "parameters": dict(model.parameters), "analysis": a,
               "least_delta": float(np.min(md.delta)) if len(md) else math.nan,
               "least_zeta": float(md.zeta[np.argmin(md.delta)]) if len(md) else math.nan,
               "freqs": [float(x) for x in md.freq_hz],
               "posture": {p["name"]: p["angle_deg"] for p in rep["posture"]},
               "out_of_range": rep["out_of_range"],
               "actuator": [r["tension"] for r in rep["actuator"]]}
    return blocks, summary


def _mode_label(k, md):
    """Panel title of mode k by its kind: damped frequency and ζ, the time constant of a real
    mode, or rigid-body."""
    s = complex(md.eigenvalues[k])
    kind = md.kind[k]
    if kind in ("overdamped", "divergence") and s.real != 0:
        what = "overdamped, decays" if kind == "overdamped" else "DIVERGENCE, grows"
        return f"mode {k + 1}: {what}, τ = 1/|s| = {1e3 / abs(s.real):.4g} ms"
    if kind == "rigid-body":
        return f"mode {k + 1}: rigid-body (s ≈ 0 within its tolerance)"
    return (f"mode {k + 1}: ω_d/2π = {abs(s.imag) / (2 * math.pi):.4g} Hz, "
            f"ζ = {float(md.zeta[k]):.3g}" + (" (FLUTTER)" if kind == "flutter" else ""))


def _spatial_draw():
    """The three-view drawing of spatial models (mbseig.plots.spatial), imported when needed."""
    from ..plots import spatial as plots_spatial

    return plots_spatial.spatial_modes


def _statics_text(eq):
    """One paragraph on how the equilibrium was found and whether it is statically stable."""
    tol = eq.tolerances
    path = eq.path or {}
    start = ("the commanded posture of the inverse statics" if getattr(eq.model, "drivers", ())
             else "the case's positions")
    how = {"newton": f"Newton from {start}"}.get(eq.method, eq.method)
    if path.get("load_steps"):
        how += f" ({path['load_steps']} load steps; the direct Newton failed: {path.get('direct')})"
    st = eq.static or {}
    verdict = st.get("verdict")
    stab = {"stable": "statically stable (the reduced tangent stiffness is positive definite)",
            "unstable": f"statically UNSTABLE ({st.get('index')} direction(s) of negative stiffness)",
            "neutral": "statically neutral (a zero stiffness)",
            "undetermined": ("statics cannot decide (non-symmetric stiffness with an even number "
                             "of negative real eigenvalues): see the modes"),
            "not examined": "not examined (above the dense limit)"}.get(verdict, "–")
    text = (f"Statics: {how}, {eq.iterations} Newton iterations; converged when "
            f"{tol.get('criterion', '')} (tol = {tol.get('tol', 0):g}, xtol = "
            f"{tol.get('xtol', 0):g}); final Newton correction {eq.correction:.2g} of the model's "
            f"size. The equilibrium is {stab}.")
    for note in eq.notes:
        text += f" {note[0].upper() + note[1:]}."
    return text


def _describe(case, config):
    return str(case.configurations.get(config, {}).get("description", ""))


def _check_blocks(a, run_check):
    blocks = [("h3", "Time-domain check")]
    if not run_check:
        blocks.append(("p", "Time-domain check not run (report built with --no-check)."))
        return blocks
    res = check_modes(a.model, a.eq, a.linear, a.modes)
    rows = []
    for m in res.modes:
        if m.skipped:
            rows.append([str(m.index), m.kind, _fmt(m.predicted_delta), "–", "–",
                         _fmt(m.predicted_omega), "–", "–", f"skipped ({m.skipped})"])
            continue
        rows.append([str(m.index), m.kind, _fmt(m.predicted_delta), _fmt(m.measured_delta),
                     f"{m.rel_error_delta:.1e}", _fmt(m.predicted_omega, 8),
                     _fmt(m.measured_omega, 8), f"{m.rel_error_omega:.1e}",
                     "pass" if m.passed else "**FAIL**"])
    tol = res.tolerances
    blocks.append(("p", f"Each mode is excited alone in the nonlinear model ({res.integrator}, "
                        f"rtol {tol['ode_rtol']:g}) and its modal coordinate fitted; tolerances: δ "
                        f"{tol['delta_rtol']:g} relative, ω {tol['omega_rtol']:g} relative. "
                        f"Result: {'all passed' if res.passed else 'FAILED for ' + str(res.failed)}."))
    blocks.append(("table", ["mode", "kind", "δ predicted [1/s]", "δ measured [1/s]",
                             "δ rel. err. [–]", "ω predicted [rad/s]", "ω measured [rad/s]",
                             "ω rel. err. [–]", "result"], rows))
    return blocks


# ---------------------------------------------------------------------------------------------
def _study_blocks(case, study, out_dir, stem, jobs, units):
    kind = "compare" if "compare" in study else "sweep"
    config = study.get("config")
    title = study.get("title", f"{kind} on {config}")
    blocks = [("h2", title)]
    if kind == "compare":
        return blocks + _compare_blocks(case, config), {"title": title}
    name = study["sweep"]
    lo, hi = study["range"]
    values = np.linspace(float(lo), float(hi), int(study["count"]))
    axes = [(name, values)]
    lines = study.get("lines", {})
    for lname, lvals in lines.items():
        axes.append((lname, np.asarray(lvals, dtype=float)))
    curve_values = _curve_values(axes[1][1]) if len(axes) == 2 else None
    res = run_sweep(case, axes, config=config, jobs=jobs,
                    xtol_rel=float(study.get("xtol_rel", 1e-10)), curve_values=curve_values)
    sdir = out_dir / f"{stem}_{config}_{name}"
    paths = write_outputs(res, sdir, units=units)
    xtol = res.tolerances["xtol"]
    unit = units.get(name)
    direction = 1.0 if values[-1] >= values[0] else -1.0
    rows, crit = [], []
    for l, line in enumerate(res.lines):
        bs = sorted((b for b in res.boundaries if b["line"] == l and b["stability"] == "loss"),
                    key=lambda b: (b["value"] - values[0]) * direction)
        first = bs[0] if bs else None
        rom = _rom_exit(case, config, line, name, values, res.points[l], xtol)
        failed = sum(1 for pt in res.points[l] if pt.get("error"))
        label = ", ".join(f"{k} = " + with_unit(f"{v:g}", units.get(k)) for k, v in line.items()) or "–"
        freq = "–" if first is None else f"{abs(first['eigenvalue'][1]) / (2 * math.pi):.5g}"
        band = ("–" if first is None or first["band"][0] == first["band"][1] else
                f"{first['band'][0]:.10g} … {first['band'][1]:.10g}")
        rows.append([label,
                     "stable over the range" if first is None else with_unit(f"{first['value']:.10g}", unit),
                     "–" if first is None else first["kind"] + (
                         "" if first.get("event") == "crossing" else f" ({first['event']})"),
                     freq, band,
                     "inside over the range" if rom is None else
                     with_unit(f"{rom['value']:.8g}", unit) + f" ({rom['joint']})",
                     str(failed)])
        crit.append({"line": line, "critical": None if first is None else first["value"],
                     "kind": None if first is None else first["kind"], "rom": rom,
                     "failed": failed})
    n_fold = sum(1 for f in res.folds if f["type"] == "fold")
    blocks.append(("p", f"{name} from {values[0]:g} to {with_unit(f'{values[-1]:g}', unit)} "
                        f"({len(values)} points per line) on "
                        f"{config}, each line followed by continuation from its first equilibrium "
                        f"(tangent predictor, pseudo-arclength through folds; {n_fold} fold(s) "
                        f"found); modes tracked by MAC; each boundary located where Re s = 0 of "
                        f"the crossing mode (or where the two eigenvalues of an undamped pair "
                        f"collide) by Brent's method to xtol = {xtol:.3g}, with the band where "
                        f"the mode is critical within its tolerance beside it; range-of-motion exit "
                        f"by Brent's method on the smallest joint margin to the same xtol."))
    u = f" [{unit}]" if unit and unit != "1" else ""
    blocks.append(("table", ["line", f"critical {name}", "instability",
                             "ω_d/2π at onset [Hz]", f"critical band{u}",
                             f"{name} where the posture leaves the range of motion",
                             "failed points"], rows))
    curve_sum = []
    for c in res.curves:
        pts = [p for p in c["points"] if p["value"] is not None]
        curve_sum.append({"along": c["along"], "points": [(p["p2"], p["value"]) for p in pts]})
        blocks.append(("p", f"The {c['kind']} boundary of the first line, followed across "
                            f"{c['along']} (two-parameter continuation: each point located again "
                            f"from the secant prediction of the last two; "
                            f"{len(pts)} of {len(c['points'])} points found):"))
        ua = units.get(c["along"])
        blocks.append(("table", [c["along"] + (f" [{ua}]" if ua and ua != "1" else " [–]" if ua else ""),
                                 f"critical {name}{u}", "test function"],
                       [[f"{p['p2']:.6g}", f"{p['value']:.10g}", p.get("test") or "–"] for p in pts]))
    captions = {"root_locus": "root locus (one colour a mode, numbered as the mode tables at the "
                              "first value; one line style a line)",
                "modes_vs_parameter": "damped frequency ω_d/2π and damping δ of each mode",
                "bifurcation": "bifurcation diagram (dashed where unstable)",
                "stability_map": "stability map: spectral abscissa on the grid",
                "stability_chart": "stability chart from the followed boundaries"}
    for p in paths:
        if p.suffix == ".png":
            blocks.append(("img", p, f"{title}: {captions.get(p.stem, p.stem.replace('_', ' '))}"))
    return blocks, {"title": title, "parameter": name, "config": config, "critical": crit,
                    "curves": curve_sum}


def _curve_values(line_values):
    """The second axis' values at which a boundary is followed: the lines' values with two
    more between each pair (geometric between positive values a decade or more apart, and down
    to 0 through 1/10 and 1/100 of the smallest positive one), from the first line outwards."""
    vals = [float(v) for v in line_values]
    out = [vals[0]]
    for a, b in zip(vals, vals[1:]):
        if a > 0 and b > 0 and max(a, b) / min(a, b) >= 10:
            mids = list(np.geomspace(a, b, 4)[1:-1])
        elif b == 0 and a > 0:
            mids = [a / 10, a / 100]
        else:
            mids = list(np.linspace(a, b, 4)[1:-1])
        out += [float(m) for m in mids] + [b]
    return out


def _rom_exit(case, config, line, name, values, points, xtol):
    """First parameter value where a joint leaves its range of motion (None if never); each
    equilibrium of the search is started from the bracket's own (same branch)."""
    from scipy.optimize import brentq

    from ..studies.boundaries import Evaluator

    for k in range(len(values) - 1):
        a, b = points[k], points[k + 1]
        if a.get("error") or b.get("error") or a.get("segment") != b.get("segment"):
            continue
        if not a["out_of_range"] and b["out_of_range"]:
            ev = Evaluator(case, config, line, name, [(values[k], a["q"]), (values[k + 1], b["q"])])

            def margin(p):
                pt = ev(p)
                model = ev.make(p)
                rows = [r for r in posture(model, pt["q"]) if r["margin_deg"] is not None]
                return min(r["margin_deg"] for r in rows) if rows else math.inf

            root = brentq(margin, values[k], values[k + 1], xtol=xtol)
            return {"value": float(root), "joint": b["out_of_range"][0]}
    if points and not points[0].get("error") and points[0]["out_of_range"]:
        return {"value": float(values[0]), "joint": points[0]["out_of_range"][0]}
    return None


def _compare_blocks(case, config):
    model = case.build(config)
    eq = equilibrium(model)
    with_h = modes(*_mpq(linearize(model, eq)))
    without = modes(*_mpq(linearize(model, eq, constraint_stiffness=False)))
    from scipy.optimize import linear_sum_assignment

    # pair each eigenvalue with its nearest counterpart (listings differ when a pair turns real)
    sa, sb = with_h.all_eigenvalues, without.all_eigenvalues
    ia, ib = linear_sum_assignment(np.abs(sa[:, None] - sb[None, :]))
    pairs = sorted(((sa[i], sb[j]) for i, j in zip(ia, ib) if sa[i].imag >= 0),
                   key=lambda p: (abs(p[0]), p[0].imag))
    rows = []
    for k, (a, b) in enumerate(pairs):
        rel = abs(a - b) / abs(a) if a is not None and b is not None and abs(a) > 0 else None
        rows.append([str(k + 1), "–" if a is None else f"{a.real:.6g} {a.imag:+.6g}i",
                     "–" if b is None else f"{b.real:.6g} {b.imag:+.6g}i",
                     "–" if rel is None else f"{rel:.3g}"])
    lam_max = float(np.max(np.abs(eq.lam))) if eq.lam.size else 0.0
    return [("p", f"Eigenvalues of {config} with the constraint-force stiffness Σ λ ∇²Φ (correct) "
                  f"and without it (the common omission); largest multiplier |λ| = {lam_max:.4g}. "
                  f"Verdict with: {with_h.verdict}; without: {without.verdict}."),
            ("table", ["#", "s with Σλ∇²Φ", "s without", "|Δs|/|s|"], rows)]


def _mpq(lin):
    return lin.M, lin.P, lin.Q


# ---------------------------------------------------------------------------------------------
def _clean(blocks):
    out = []
    for b in blocks:
        if b[0] == "table":
            out.append(("table", [user_names(h) for h in b[1]],
                        [[user_names(str(x)) for x in r] for r in b[2]]))
        elif b[0] == "img":
            out.append(("img", b[1], user_names(b[2])))
        elif b[0] == "toc":
            out.append(b)
        else:
            out.append((b[0], user_names(b[1])))
    return out


def provenance(case) -> dict:
    """mbseig version, date (UTC; ``SOURCE_DATE_EPOCH`` when set, for reproducible builds) and
    the SHA-256 of the case file: what a reader needs to know which inputs made the report."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        ver = version("mbseig")
    except PackageNotFoundError:  # not installed as a distribution (a source tree)
        ver = "unknown"
    epoch = os.environ.get("SOURCE_DATE_EPOCH")
    try:
        stamp = float(epoch) if epoch else time.time()
    except ValueError:
        stamp = time.time()
    date = time.strftime("%Y-%m-%d", time.gmtime(stamp))
    try:
        digest = hashlib.sha256(Path(case.source).read_bytes()).hexdigest()
    except (OSError, TypeError):
        digest = "unavailable"
    import numpy
    import scipy

    return {"mbseig": ver, "date": date, "case": Path(str(case.source)).name,
            "sha256": digest, "numpy": numpy.__version__, "scipy": scipy.__version__}


def build_report(case, *, configs=None, out_dir, run_check=True, jobs=None, studies=True,
                 sensitivities=True):
    """Blocks of the report of ``case`` (a path or a parsed :class:`~mbseig.casefile.CaseSpec`,
    read once) for ``configs`` (list of names; [None] for the base): title, provenance, table
    of contents, summary, comparison, one section a configuration, the studies."""
    case = as_spec(case)
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    stem = case.name
    configs = configs or [None]
    units = parameter_units(case)
    base = case.build(configs[0])
    prov = provenance(case)
    head = [("h1", f"Stability report: {stem}"),
            ("p", base.description or ""),
            ("p", f"Generated by mbseig {prov['mbseig']} on {prov['date']} (UTC) from "
                  f"`{prov['case']}` (SHA-256 {prov['sha256'][:16]}…; numpy {prov['numpy']}, "
                  f"scipy {prov['scipy']}). Configurations: "
                  + ", ".join(c or "base" for c in configs) + ". Regenerate with `mbseig report "
                  + f"cases/{prov['case']}" + (" --all-configs" if len(configs) > 1 else "") + "`.")]
    summaries, cfg_blocks = [], []
    for c in configs:
        b, s = _config_blocks(case, c, out_dir, run_check=run_check, stem=stem, units=units)
        cfg_blocks += b
        summaries.append(s)
    study_blocks, study_sums = [], []
    if studies:
        for st in getattr(base, "report", {}).get("studies", []):  # a linear case has no [report]
            if st.get("config") not in configs and not (len(configs) > 1):
                continue
            b, s = _study_blocks(case, st, out_dir, stem, jobs, units)
            study_blocks += b
            study_sums.append(s)
    body = _summary(case, summaries, study_sums, units, sensitivities)
    if len(configs) > 1:
        body += _comparison(summaries, study_sums, units)
    body += cfg_blocks + study_blocks
    toc = [("h2", "Contents"), ("toc", [(2, user_names(b[1])) for b in body if b[0] == "h2"])]
    return _clean(head + toc + body)


def _margin_text(name, current, crit, unit, kind):
    """``f: 0.786 N to flutter (f* = 1.786 N, +79 %)``."""
    d = crit - current
    rel = f", {100 * d / abs(current):+.0f} % of the present value" if current else ""
    return (f"{name} = {with_unit(_fmt(current, 5), unit)} → {name}* = "
            f"{with_unit(_fmt(crit, 6), unit)} ({kind}): margin {with_unit(f'{d:+.4g}', unit)}{rel}")


def _summary(case, summaries, study_sums, units, sensitivities=True):
    """The summary first: per configuration the verdict, the least-damped mode, the margins to
    every boundary the studies found (with units) and, when :mod:`mbseig.studies.design` is
    there, the parameter that moves the least stable mode most."""
    rows = []
    notes = []
    for s in summaries:
        lm = s["least_mode"]
        if lm is None:
            least = "–"
        elif lm["fd"] > 0:
            least = (f"mode {lm['mode']} ({lm['kind']}): ω_n/2π = {lm['fn']:.4g} Hz, "
                     f"ω_d/2π = {lm['fd']:.4g} Hz, ζ = {lm['zeta']:.3g}, δ = {lm['delta']:.4g} 1/s")
        else:
            least = (f"mode {lm['mode']} ({lm['kind']}): ω_n/2π = {lm['fn']:.4g} Hz, "
                     f"δ = {lm['delta']:.4g} 1/s")
        margins = []
        for st in study_sums:
            if st.get("config") != s["config"] or "critical" not in st:
                continue
            name = st["parameter"]
            unit = units.get(name)
            current = s["parameters"].get(name)
            own = [c for c in st["critical"]
                   if all(s["parameters"].get(k) is not None and
                          abs(float(s["parameters"][k]) - float(v)) <= 1e-12 * (1 + abs(float(v)))
                          for k, v in c["line"].items())] or st["critical"]
            for c in own:
                where = ", ".join(f"{k} = " + with_unit(f"{v:g}", units.get(k))
                                  for k, v in c["line"].items())
                if c["critical"] is None:
                    margins.append(f"{name}: no boundary in the swept range" + (f" ({where})" if where else ""))
                elif current is not None and isinstance(current, (int, float)):
                    margins.append(_margin_text(name, float(current), c["critical"], unit, c["kind"])
                                   + (f" at {where}" if where and len(own) > 1 else ""))
                else:
                    margins.append(f"{name}* = {with_unit(_fmt(c['critical'], 6), unit)} ({c['kind']})")
                if c.get("rom"):
                    margins.append(f"{c['rom']['joint']} leaves its range of motion at {name} = "
                                   + with_unit(_fmt(c["rom"]["value"], 6), unit))
        rom = ("inside" if not s["out_of_range"] else "OUTSIDE for " + ", ".join(s["out_of_range"]))
        rows.append([s["config"], f"**{s['verdict']}**" if s["verdict"] != "stable" else s["verdict"],
                     least, rom, "; ".join(margins) or "no boundary study"])
        sens = _sensitivity_sentence(case, s, units) if sensitivities else None
        if sens:
            notes.append(sens)
    blocks = [("h2", "Summary"),
              ("table", ["configuration", "verdict", "least-damped mode", "range of motion",
                         "margins to the boundaries found (present value → critical value)"], rows)]
    if notes:
        blocks += [("p", n) for n in notes]
    elif not sensitivities:
        blocks.append(("p", "Eigenvalue sensitivities not computed (--no-sensitivities)."))
    return blocks


def _sensitivity_sentence(case, s, units):
    """∂s/∂p of the least-damped mode for every parameter (mbseig.studies.design): the
    parameter that moves Re s most per relative change, with units."""
    from ..studies.design import eigen_sensitivities

    if s["least"] is None:
        return None
    config = None if s["config"] == "base" else s["config"]
    try:
        sens = eigen_sensitivities(case, config=config, analysis=s.get("analysis"))
    except MbseigError as exc:  # e.g. a model kept sparse: said in the report, not hidden
        return f"{s['config']}: sensitivities not computed ({type(exc).__name__}: {exc})."
    k = s["least"]
    ranked = []
    for p, ds in (sens or {}).items():
        ds = np.asarray(ds)
        if ds.ndim == 0 or k >= ds.size:
            continue
        value = s["parameters"].get(p)
        if not isinstance(value, (int, float)) or not value or not np.isfinite(ds[k]):
            continue  # a parameter at 0 (a load switched off) has no relative change
        # the change of Re s for a 1 % change of p: |p| · ∂Re s/∂p / 100
        per_pct = ds[k].real * abs(value) / 100
        ranked.append((abs(per_pct), p, complex(ds[k]), value, per_pct))
    if not ranked:
        return None
    ranked.sort(key=lambda r: -r[0])
    parts = []
    for _, p, d, value, per_pct in ranked[:3]:
        unit = units.get(p)
        per = f"1/s per {unit}" if unit and unit != "1" else "1/s"
        effect = "destabilizes" if d.real > 0 else "stabilizes"
        step = f"+1 % moves Re s by {per_pct:+.3g} 1/s"
        parts.append(f"{p} (= {with_unit(_fmt(value, 5), unit)}; ∂Re s/∂{p} = {d.real:.4g} {per}; "
                     f"{step}; increasing it {effect} the mode)")
    return (f"{s['config']}: the parameters that move the least-damped mode (mode {k + 1}, "
            f"Re s = {-s['least_mode']['delta']:.4g} 1/s) most, per relative change: "
            + "; ".join(parts) + " (parameters at 0 left out).")


def _comparison(summaries, study_sums, units):
    rows = []
    for s in summaries:
        crit = []
        for st in study_sums:
            if st.get("config") == s["config"] and "critical" in st:
                for c in st["critical"]:
                    where = ", ".join(f"{k} = " + with_unit(f"{v:g}", units.get(k))
                                      for k, v in c["line"].items())
                    val = ("none in range" if c["critical"] is None else
                           with_unit(f"{c['critical']:.6g}", units.get(st["parameter"])))
                    crit.append(f"{st['parameter']}* = {val}" + (f" ({where})" if where else ""))
        rows.append([s["config"], str(s["dof"]), s["verdict"], _fmt(s["least_delta"], 5),
                     _fmt(s["least_zeta"], 4), ", ".join(f"{f:.4g}" for f in s["freqs"]),
                     ", ".join(f"{k} {v:.2f}" for k, v in s["posture"].items()),
                     ", ".join(s["out_of_range"]) or "none",
                     ", ".join(f"{t:.4g}" for t in s["actuator"]) or "–",
                     "; ".join(crit) or "–"])
    blocks = [("h2", "Comparison of the configurations"),
              ("table", ["config", "DOF", "verdict", "least δ [1/s]", "its ζ [–]",
                         "ω_d/2π of the modes [Hz]", "posture [deg]", "outside ROM",
                         "actuator tension [N]", "critical parameters"], rows)]
    blocks += _findings(study_sums, units)
    return blocks


def _findings(study_sums, units):
    """What the follower-load study says about damping (the destabilizing-damping paradox)."""
    out = []
    for st in study_sums:
        crit = st.get("critical") or []
        lines = [c for c in crit if "damping_scale" in c["line"] and c["critical"] is not None]
        if len(lines) < 2:
            continue
        by = sorted(lines, key=lambda c: -c["line"]["damping_scale"])
        u = units.get(st["parameter"])
        def val(x, u=u):
            return with_unit(f"{x:.6g}", u)
        text = [f"{st['parameter']}* = {val(c['critical'])} at damping scale "
                f"{c['line']['damping_scale']:g}" for c in by]
        msg = "Critical load against the damping scale: " + "; ".join(text) + ". "
        zero = next((c for c in by if c["line"]["damping_scale"] == 0), None)
        curve = next((c for c in st.get("curves", []) if c["along"] == "damping_scale"), None)
        small = [c for c in by if c["line"]["damping_scale"] > 0]
        if curve and curve["points"]:
            pos = [p for p in curve["points"] if p[0] > 0]
            if pos:
                s_min, f_min = min(pos)
                msg += (f"Followed continuously in the damping scale, the critical load is "
                        f"{val(f_min)} at the smallest scale {s_min:g}. ")
                small = small + [{"critical": f_min, "line": {"damping_scale": s_min}}]
        if zero is not None:
            msg += f"The undamped flutter load (damping scale 0) is {val(zero['critical'])}. "
            lim = min(small, key=lambda c: c["line"]["damping_scale"])["critical"] if small else None
            if lim is not None and lim < zero["critical"] * (1 - 1e-6):
                msg += (f"As the damping tends to zero the critical load tends to about "
                        f"{with_unit(f'{lim:.5g}', u)}, "
                        f"below the undamped value: the destabilizing effect of small damping on "
                        f"a follower-loaded (circulatory) system. A design that relies on the "
                        f"dampers for its margin loses it when they are small.")
            elif lim is not None:
                msg += ("As the damping tends to zero the critical load does not fall below the "
                        "undamped value here.")
        out.append(("p", msg))
    return out


# ---------------------------------------------------------------------------------------------
def write_report(case, *, out_dir=None, configs=None, all_configs=False, run_check=True,
                 jobs=None, studies=True, sensitivities=True):
    """Write report.md and report.html (default directory reports/<case>); returns their paths.

    ``case`` is a path or a parsed :class:`~mbseig.casefile.CaseSpec`; it is read once."""
    case = as_spec(case)
    if all_configs:  # the base case first, then every named configuration
        configs = [None] + sorted(case.configurations)
    out = Path(out_dir) if out_dir else Path("reports") / case.name
    blocks = build_report(case, configs=configs, out_dir=out, run_check=run_check, jobs=jobs,
                          studies=studies, sensitivities=sensitivities)
    md = out / "report.md"
    md.write_text(render_markdown(blocks, out))
    page = out / "report.html"
    page.write_text(render_html(blocks, f"Stability report: {case.name}"))
    return md, page
