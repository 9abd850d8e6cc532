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

What a person reads follows the zero rule (DESIGN §6, :mod:`mbseig.display`): every listing a
report shows is a :class:`ModeListing` (the modes of a rest or a steady motion alike) with the
error bounds of Re s (and δ) and of Im s (and |s|) beside the raw values; the least-damped
mode (:func:`least_damped`) is the counted mode (not rigid-body by construction) of smallest δ
as read, the first listed among equals; sensitivities carry the bound
:func:`mbseig.studies.design.eigen_sensitivities` gives them (``with_bounds=True``).
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
           "least_mode_sensitivities", "ModeListing", "listing_of_modes", "listing_of_rows",
           "least_damped", "least_mode_record"]

NO_REACTIONS = dict(posture=[], out_of_range=[], drivers=[], actuator=[], pins=[], constraints=[])


@dataclass(frozen=True, eq=False)
class ModeListing:
    """The listed modes as a report shows them, whatever the motion: raw values with the error
    bounds of the zero rule (``bound_re``: of Re s and δ; ``bound_im``: of Im s and |s|), the
    stability tolerance that decided each mode, its kind, the coordinates that move most (user
    names) and the declared rigid-body direction (None for a counted mode)."""

    eigenvalues: np.ndarray  # a pair once, Im s ≥ 0
    delta: np.ndarray
    bound_re: np.ndarray
    bound_im: np.ndarray
    tolerance: np.ndarray
    stability: list
    kind: list
    dominant: list  # per mode: [name, ...]
    rigid_body: list
    verdict: object  # a mbseig.modal.result.Verdict
    rule: str = ""  # the rule of the tolerance, in words

    def __len__(self):
        return int(self.eigenvalues.size)


def listing_of_modes(md) -> ModeListing:
    """The :class:`ModeListing` of a :class:`~mbseig.modal.result.Modes` (its own bounds,
    :meth:`~mbseig.modal.result.Modes.zero_bounds`)."""
    from ..modal import tolerance_rule

    bre, bim = md.zero_bounds()
    n = len(md)
    return ModeListing(np.asarray(md.eigenvalues, complex), np.asarray(md.delta, float), bre, bim,
                       np.asarray(md.tolerance, float), list(md.stability), list(md.kind),
                       [[nm for nm, _ in d] for d in md.dominant],
                       list(md.rigid_body) if md.rigid_body else [None] * n, md.verdict,
                       tolerance_rule(md.tolerances))


def listing_of_rows(rows, verdict, rule="") -> ModeListing:
    """The :class:`ModeListing` of mode rows (dicts of ``modes --json``, as a steady motion
    lists them): each row's ``tolerance`` bounds both parts, as it decided both (Im s within
    it is 0, |s| within it is rigid-body: :func:`mbseig.studies.steady_modes.mode_rows`)."""
    tol = np.array([float(r["tolerance"]) for r in rows])
    return ModeListing(np.array([complex(*r["eigenvalue"]) for r in rows], complex),
                       np.array([float(r["delta"]) for r in rows]), tol, tol.copy(), tol.copy(),
                       [r["stability"] for r in rows], [r["kind"] for r in rows],
                       [[d[0] for d in r.get("dominant") or ()] for r in rows],
                       [r.get("rigid_body") for r in rows], verdict, rule)


def least_damped(listing):
    """Index of the least-damped counted mode: the smallest δ as a person reads it (the zero
    rule), the modes that are rigid-body by construction skipped, the first listed among
    equals (so rounding residue never picks it); None when no mode is counted."""
    from ..display import shown_array

    d = shown_array(listing.delta, listing.bound_re)
    counted = [k for k in range(len(listing)) if listing.rigid_body[k] is None]
    return min(counted, key=lambda k: (d[k], k)) if counted else None


def least_mode_record(listing, k):
    """The figures of mode k for the summary (None for None): raw values, with the bounds."""
    if k is None:
        return None
    s = complex(listing.eigenvalues[k])
    wn = abs(s)
    return {"mode": k + 1, "delta": float(listing.delta[k]), "kind": listing.kind[k],
            "zeta": float(listing.delta[k] / wn) if wn > 0 else 0.0,
            "fn": wn / (2 * math.pi), "fd": abs(s.imag) / (2 * math.pi),
            "bound_re": float(listing.bound_re[k]), "bound_im": float(listing.bound_im[k]),
            "margin": float(listing.delta[k] - listing.tolerance[k]),
            "eigenvalue": [float(s.real), abs(float(s.imag))]}


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
    listing: object = internal()


def study_configuration(case, config, *, run_check=True) -> ConfigurationStudy:
    """Analyse ``config`` of ``case`` (a :class:`~mbseig.casefile.CaseSpec`) for the report."""
    a = analyze(case, config=config)
    model, eq, lin, md = a.model, a.eq, a.linear, a.modes
    linear_case = isinstance(model, LinearCase)  # matrices only: no posture, reactions or drawing
    rep = NO_REACTIONS if linear_case else reactions(model, eq)
    listing = listing_of_modes(md)
    least = least_damped(listing)
    least_mode = least_mode_record(listing, least)
    return ConfigurationStudy(
        config=config or "base", dof=lin.dof, verdict=md.verdict, least=least,
        least_mode=least_mode, parameters=dict(model.parameters),
        least_delta=math.nan if least is None else float(md.delta[least]),
        least_zeta=math.nan if least is None else least_mode["zeta"],
        freqs=[float(x) for x in md.freq_hz],
        posture={p["name"]: p["angle_deg"] for p in rep["posture"]},
        out_of_range=rep["out_of_range"], actuator=[r["tension"] for r in rep["actuator"]],
        analysis=a, reactions=rep,
        check=check_modes(a.model, a.eq, a.linear, a.modes) if run_check else None,
        linear_case=linear_case, reaction_zero=_reaction_zero(eq, rep), listing=listing)


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
    for a, b in zip(vals, vals[1:], strict=False):
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
    for li, line in enumerate(res.lines):
        bs = sorted((b for b in res.boundaries if b["line"] == li and b["stability"] == "loss"),
                    key=lambda b: (b["value"] - values[0]) * direction)
        first = bs[0] if bs else None
        crit.append({"line": line, "critical": None if first is None else first["value"],
                     "kind": None if first is None else first["kind"],
                     "rom": rom_exit(case, config, line, name, values, res.points[li], xtol),
                     "failed": sum(1 for pt in res.points[li] if pt.get("error")),
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

            def margin(p, ev=ev):
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
    bounds: list = internal()  # per pair: ((Re, Im) bounds with, (Re, Im) bounds without)


def compare_study(case, config) -> CompareStudy:
    from scipy.optimize import linear_sum_assignment

    model = case.build(config)
    eq = equilibrium(model)
    with_h = modes(*_mpq(linearize(model, eq)))
    without = modes(*_mpq(linearize(model, eq, constraint_stiffness=False)))
    # pair each eigenvalue with its nearest counterpart (listings differ when a pair turns real)
    sa, sb = with_h.all_eigenvalues, without.all_eigenvalues
    ia, ib = linear_sum_assignment(np.abs(sa[:, None] - sb[None, :]))
    ba, bb = _listed_bounds(with_h, sa), _listed_bounds(without, sb)
    rows = sorted(((sa[i], sb[j], ba[i], bb[j]) for i, j in zip(ia, ib, strict=True)
                   if sa[i].imag >= 0),
                  key=lambda p: (abs(p[0]), p[0].imag))
    lam_max = float(np.max(np.abs(eq.lam))) if eq.lam.size else 0.0
    return CompareStudy(config=config, pairs=[(a, b) for a, b, _, _ in rows], lam_max=lam_max,
                        verdict_with=with_h.verdict, verdict_without=without.verdict,
                        bounds=[(x, y) for _, _, x, y in rows])


def _listed_bounds(md, eigenvalues):
    """(bound of Re s, bound of Im s) of each of ``eigenvalues`` (the whole spectrum of ``md``):
    those of the listed mode it is (or is the conjugate of), :meth:`Modes.zero_bounds`."""
    bre, bim = md.zero_bounds()
    listed = np.asarray(md.eigenvalues, complex)
    if listed.size == 0:
        return [(math.nan, math.nan)] * len(eigenvalues)
    out = []
    for s in eigenvalues:
        k = int(np.argmin(np.minimum(np.abs(listed - s), np.abs(listed - np.conj(s)))))
        out.append((float(bre[k]), float(bim[k])))
    return out


def _mpq(lin):
    return lin.M, lin.P, lin.Q


def least_mode_sensitivities(case, summary: ConfigurationStudy, *, top=3):
    """∂s/∂p of the least-damped mode for every parameter (:mod:`mbseig.studies.design`),
    ranked by the change of Re s per 1 % change of p as a person reads it (the zero rule: a
    change within its bound is 0 and ranks last): a list of dicts ``parameter``, ``derivative``
    (∂s/∂p), ``bound`` (its absolute error bound, NaN when the sensitivities come without one),
    ``value`` (p), ``per_pct`` (the change of Re s for +1 % of p, |p| Re ∂s/∂p / 100) and
    ``per_pct_bound``; the first ``top`` (all with None).  None when there is no mode or no
    parameter enters the model; a string (what failed) when the sensitivities could not be
    computed."""
    from ..display import shown
    from .design import eigen_sensitivities

    if summary["least"] is None:
        return None
    config = None if summary["config"] == "base" else summary["config"]
    analysis = summary.get("analysis")
    if getattr(analysis, "refinement", None):
        # eigen_sensitivities differences the model as the case builds it, not the refined
        # mesh the modes come from (elements = "auto"): their sizes differ, so none is given
        return ("the mesh was refined (elements = \"auto\"); the sensitivities are "
                "computed on the case's own mesh only")
    import inspect

    try:
        if "with_bounds" in inspect.signature(eigen_sensitivities).parameters:
            sens, bounds = eigen_sensitivities(case, config=config,
                                               analysis=summary.get("analysis"), with_bounds=True)
        else:  # sensitivities without their bound: printed as computed, and said so
            sens = eigen_sensitivities(case, config=config, analysis=summary.get("analysis"))
            bounds = {}
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
        b = np.asarray(bounds.get(p, np.full(ds.size, np.nan)), float)
        bound = float(b[k]) if b.ndim and k < b.size else float(b)
        # the change of Re s for a 1 % change of p: |p| · ∂Re s/∂p / 100
        per_pct = ds[k].real * abs(value) / 100
        per_bound = bound * abs(value) / 100
        ranked.append({"parameter": p, "derivative": complex(ds[k]), "bound": bound,
                       "value": value, "per_pct": float(per_pct), "per_pct_bound": per_bound})
    if not ranked:
        return None
    ranked.sort(key=lambda r: -abs(shown(r["per_pct"], r["per_pct_bound"])))
    return ranked[:top]
