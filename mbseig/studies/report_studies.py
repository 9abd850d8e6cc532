"""What a stability report shows, computed here (the report module only formats it).

- :func:`study_configuration` → :class:`ConfigurationStudy`: one configuration analysed
  (equilibrium, reactions, modes, the least-damped mode, the time-domain check);
- :func:`sweep_study` → :class:`SweepStudy`: a ``[[report.studies]]`` sweep with the first loss
  of stability of every line and where the posture leaves its range of motion
  (:func:`rom_exit`: Brent's method on the smallest joint margin);
- :func:`compare_study` → :class:`CompareStudy`: the eigenvalues with and without the
  constraint-force stiffness Σ λ ∇²Φ, paired;
- :func:`least_mode_sensitivities`: the parameters that move the least-damped mode most.

``reaction_zero`` of a :class:`ConfigurationStudy` is the error bound of its reactions:
tol · max |value| over the pin forces and the constraint reactions, with tol the equilibrium's
convergence tolerance (``eq.tolerances["tol"]``, every constraint and force balanced to that
fraction of its scale), so a value below it is rounding residue (printed as 0).  The
least-damped mode's ``eigenvalue`` is kept as [Re s, Im s] (upper half-plane) for the summary
figure.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..check import check_modes
from ..errors import MbseigError
from ..linear import linearize
from ..modal import modes
from ..model.linear_case import LinearCase
from ..records import Record, internal
from ..statics import equilibrium
from ..statics.reactions import posture, reactions
from .pipeline import analyze

__all__ = ["ConfigurationStudy", "study_configuration", "SweepStudy", "sweep_study",
           "CompareStudy", "compare_study", "rom_exit", "curve_values",
           "least_mode_sensitivities"]

NO_REACTIONS = dict(posture=[], out_of_range=[], drivers=[], actuator=[], pins=[], constraints=[])


@dataclass(frozen=True, eq=False)
class ConfigurationStudy(Record):
    """One configuration of a report: the verdict, the least-damped mode (``least`` its index,
    ``least_mode`` its figures), the parameters, posture, range-of-motion flags and actuator
    tensions; the analysis, the reactions and the time-domain check kept for the sections."""

    config: str
    dof: int
    verdict: str
    least: int | None
    least_mode: dict | None
    parameters: dict
    least_delta: float
    least_zeta: float
    freqs: list
    posture: dict
    out_of_range: list
    actuator: list
    analysis: object = internal()
    reactions: dict = internal()
    check: object = internal()
    linear_case: bool = False
    reaction_zero: float = 0.0


def study_configuration(case, config, *, run_check=True) -> ConfigurationStudy:
    """Analyse ``config`` of ``case`` (a :class:`~mbseig.casefile.CaseSpec`) for the report."""
    a = analyze(case, config=config)
    model, eq, lin, md = a.model, a.eq, a.linear, a.modes
    linear_case = isinstance(model, LinearCase)  # matrices only: no posture, reactions or drawing
    rep = NO_REACTIONS if linear_case else reactions(model, eq)
    least = int(np.argmin(md.delta)) if len(md) else None
    least_mode = None if least is None else {
        "mode": least + 1, "delta": float(md.delta[least]), "zeta": float(md.zeta[least]),
        "kind": md.kind[least], "fn": float(md.omega_n[least] / (2 * math.pi)),
        "fd": float(abs(md.eigenvalues[least].imag) / (2 * math.pi)),
        "margin": float(md.delta[least] - md.tolerance[least]),
        "eigenvalue": [float(md.eigenvalues[least].real), abs(float(md.eigenvalues[least].imag))]}
    return ConfigurationStudy(
        config=config or "base", dof=lin.dof, verdict=md.verdict, least=least,
        least_mode=least_mode, parameters=dict(model.parameters),
        least_delta=float(np.min(md.delta)) if len(md) else math.nan,
        least_zeta=float(md.zeta[np.argmin(md.delta)]) if len(md) else math.nan,
        freqs=[float(x) for x in md.freq_hz],
        posture={p["name"]: p["angle_deg"] for p in rep["posture"]},
        out_of_range=rep["out_of_range"], actuator=[r["tension"] for r in rep["actuator"]],
        analysis=a, reactions=rep,
        check=check_modes(a.model, a.eq, a.linear, a.modes) if run_check else None,
        linear_case=linear_case, reaction_zero=_reaction_zero(eq, rep))


def _reaction_zero(eq, rep) -> float:
    """The reactions' error bound (module docstring)."""
    values = [abs(float(x)) for p in rep["pins"] for x in p["force"]]
    for c in rep["constraints"]:
        v = c["reaction"]["value"]
        values += [abs(float(x)) for x in (v if isinstance(v, list) else [v])]
    tol = float((getattr(eq, "tolerances", None) or {}).get("tol", 1e-12))
    finite = [v for v in values if math.isfinite(v)]
    return tol * max(finite, default=0.0)


@dataclass(frozen=True, eq=False)
class SweepStudy(Record):
    """A report sweep: per line (``critical``) the first loss of stability (value, kind), the
    range-of-motion exit and the failed points; the boundaries followed across the second axis
    (``curves``: (p2, value) pairs); the sweep itself (``result``) for its tables and figures."""

    title: str
    parameter: str
    config: str | None
    critical: list
    curves: list
    result: object = internal()
    values: object = internal()


def curve_values(line_values):
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


def sweep_study(case, study, *, jobs=None) -> SweepStudy:
    """Run the sweep of a ``[[report.studies]]`` entry and find, on every line, the first loss
    of stability and the range-of-motion exit."""
    from .sweep import run_sweep

    config = study.get("config")
    title = study.get("title", f"sweep on {config}")
    name = study["sweep"]
    lo, hi = study["range"]
    values = np.linspace(float(lo), float(hi), int(study["count"]))
    axes = [(name, values)]
    for lname, lvals in study.get("lines", {}).items():
        axes.append((lname, np.asarray(lvals, dtype=float)))
    res = run_sweep(case, axes, config=config, jobs=jobs,
                    xtol_rel=float(study.get("xtol_rel", 1e-10)),
                    curve_values=curve_values(axes[1][1]) if len(axes) == 2 else None)
    xtol = res.tolerances["xtol"]
    direction = 1.0 if values[-1] >= values[0] else -1.0
    crit = []
    for l, line in enumerate(res.lines):
        bs = sorted((b for b in res.boundaries if b["line"] == l and b["stability"] == "loss"),
                    key=lambda b: (b["value"] - values[0]) * direction)
        first = bs[0] if bs else None
        crit.append({"line": line, "critical": None if first is None else first["value"],
                     "kind": None if first is None else first["kind"],
                     "rom": rom_exit(case, config, line, name, values, res.points[l], xtol),
                     "failed": sum(1 for pt in res.points[l] if pt.get("error")),
                     "first": first})
    curves = [{"along": c["along"],
               "points": [(p["p2"], p["value"]) for p in c["points"] if p["value"] is not None]}
              for c in res.curves]
    return SweepStudy(title=title, parameter=name, config=config, critical=crit, curves=curves,
                      result=res, values=values)


def rom_exit(case, config, line, name, values, points, xtol):
    """First parameter value where a joint leaves its range of motion (None if never); each
    equilibrium of the search is started from the bracket's own (same branch)."""
    from scipy.optimize import brentq

    from .boundaries import Evaluator

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


@dataclass(frozen=True, eq=False)
class CompareStudy(Record):
    """The eigenvalues of ``config`` with and without Σ λ ∇²Φ, paired by the assignment of
    least total distance (``pairs``: (with, without), upper half-plane, sorted by |s|)."""

    config: str | None
    pairs: list
    lam_max: float
    verdict_with: str
    verdict_without: str


def compare_study(case, config) -> CompareStudy:
    from scipy.optimize import linear_sum_assignment

    model = case.build(config)
    eq = equilibrium(model)
    with_h = modes(*_mpq(linearize(model, eq)))
    without = modes(*_mpq(linearize(model, eq, constraint_stiffness=False)))
    # pair each eigenvalue with its nearest counterpart (listings differ when a pair turns real)
    sa, sb = with_h.all_eigenvalues, without.all_eigenvalues
    ia, ib = linear_sum_assignment(np.abs(sa[:, None] - sb[None, :]))
    pairs = sorted(((sa[i], sb[j]) for i, j in zip(ia, ib) if sa[i].imag >= 0),
                   key=lambda p: (abs(p[0]), p[0].imag))
    lam_max = float(np.max(np.abs(eq.lam))) if eq.lam.size else 0.0
    return CompareStudy(config=config, pairs=pairs, lam_max=lam_max,
                        verdict_with=with_h.verdict, verdict_without=without.verdict)


def _mpq(lin):
    return lin.M, lin.P, lin.Q


def least_mode_sensitivities(case, summary: ConfigurationStudy, *, top=3):
    """∂s/∂p of the least-damped mode for every parameter (:mod:`mbseig.studies.design`),
    ranked by the change of Re s per 1 % change of p: a list of (p, ∂s/∂p, value, change per
    %), the first ``top`` (all with None); None when there is no mode or no parameter moves it; a string (what
    failed) when the sensitivities could not be computed."""
    from .design import eigen_sensitivities

    if summary["least"] is None:
        return None
    config = None if summary["config"] == "base" else summary["config"]
    try:
        sens = eigen_sensitivities(case, config=config, analysis=summary.get("analysis"))
    except MbseigError as exc:  # e.g. a model kept sparse: said in the report, not hidden
        return f"{type(exc).__name__}: {exc}"
    k = summary["least"]
    ranked = []
    for p, ds in (sens or {}).items():
        ds = np.asarray(ds)
        if ds.ndim == 0 or k >= ds.size:
            continue
        value = summary["parameters"].get(p)
        if not isinstance(value, (int, float)) or not value or not np.isfinite(ds[k]):
            continue  # a parameter at 0 (a load switched off) has no relative change
        # the change of Re s for a 1 % change of p: |p| · ∂Re s/∂p / 100
        per_pct = ds[k].real * abs(value) / 100
        ranked.append((abs(per_pct), p, complex(ds[k]), value, per_pct))
    if not ranked:
        return None
    ranked.sort(key=lambda r: -r[0])
    return [(p, d, value, per_pct) for _, p, d, value, per_pct in ranked[:top]]
