"""What the report of a periodic case shows (DESIGN §8; formatted by
:mod:`mbseig.report.periodic`): the Floquet analysis of the reference motion, the frozen-time
eigenvalues beside it (what a frozen-time analysis would conclude: not a criterion), the
time-domain check along the dominant Floquet vector, and the ``[[report.studies]]`` sweeps.

A study ``sweep = NAME, range = [a, b], count = n`` gives the Floquet verdict over the range and
its boundaries, located to ``xtol_rel`` (default 1e-8) relative
(:func:`mbseig.studies.periodic_sweep.periodic_sweep`).  With ``lines = {OTHER = [v1, ...]}`` the
sweep runs once a value of OTHER and the report also draws the stability chart over
(NAME, OTHER) from those points (the Ince–Strutt chart of a Mathieu-type system).  A
``compare = "constraint_stiffness"`` study compares two static eigenvalue problems and has no
counterpart for a periodic motion: it is listed as not applicable, not run.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..errors import CaseError
from .floquet_sweep import StabilityChart
from .periodic import periodic_analysis
from .periodic_listing import floquet_json, frozen_summary, frozen_time
from .periodic_check import check_floquet
from .periodic_sweep import periodic_sweep

__all__ = ["PeriodicStudy", "PeriodicReport", "periodic_report_data"]

SWEEP_REL_TOL = 1e-8  # default location tolerance of a study's boundaries (relative)


@dataclass(frozen=True)
class PeriodicStudy:
    """One ``[[report.studies]]`` entry run on a periodic case: ``sweeps`` holds one
    :class:`~mbseig.studies.periodic_sweep.PeriodicSweep` a line (``lines`` values, or one),
    ``chart`` the verdict grid over (sweep, line parameter) when there are lines."""

    title: str
    kind: str  # "sweep" or "not applicable"
    parameter: str | None = None
    line_parameter: str | None = None
    line_values: tuple = ()
    sweeps: tuple = ()
    chart: StabilityChart | None = None
    note: str = ""


@dataclass(frozen=True)
class PeriodicReport:
    """Everything the report of a periodic case prints (module docstring)."""

    name: str
    title: str
    description: str
    config: str | None
    analysis: object = field(repr=False)
    floquet: dict = field(repr=False)
    frozen: dict = field(repr=False)
    frozen_times: np.ndarray = field(repr=False)
    frozen_eigenvalues: np.ndarray = field(repr=False)
    check: object = None
    studies: tuple = ()
    #: per multiplier, the bound of its exponent s = ln(μ)/T propagated from the multiplier's
    #: (first order: |δs| ≤ b/(|μ| T)), for the zero rule
    exponent_bounds: tuple = ()
    #: the zero bound of the frozen-time eigenvalues: the largest of their own bounds, which
    #: made their would-be verdict (:func:`mbseig.studies.periodic_listing.frozen_summary`)
    frozen_bound: float = 0.0


def _study(spec, config, st) -> PeriodicStudy:
    title = st.get("title", f"sweep of {st.get('sweep')}")
    if "compare" in st:
        return PeriodicStudy(title, "not applicable", note=(
            f"compare = {st['compare']!r} compares static eigenvalue problems; a periodic motion "
            "has no counterpart (not run)."))
    name = st["sweep"]
    lo, hi = st["range"]
    values = np.linspace(float(lo), float(hi), int(st["count"]))
    lines = st.get("lines", {}) or {}
    if len(lines) > 1:
        raise CaseError("a study of a periodic case takes lines over one parameter",
                        element="report.studies", file=spec.source)
    rel = float(st.get("xtol_rel", SWEEP_REL_TOL))
    if not lines:
        sw = periodic_sweep(spec, name, values, config=config, rel_tol=rel)
        return PeriodicStudy(title, "sweep", name, sweeps=(sw,))
    (lname, lvals), = lines.items()
    sweeps = tuple(periodic_sweep(spec, name, values, config=config, fixed={lname: repr(float(v))},
                                  rel_tol=rel) for v in lvals)
    verdicts = np.array([[r.verdict for r in sw.results] for sw in sweeps], dtype=object).T
    rho = np.array([[r.spectral_radius for r in sw.results] for sw in sweeps]).T
    chart = StabilityChart(sweeps[0].values, np.asarray(lvals, dtype=float), verdicts, rho,
                           (name, lname))
    return PeriodicStudy(title, "sweep", name, lname, tuple(float(v) for v in lvals), sweeps,
                         chart)


def periodic_report_data(spec, *, config=None, run_check=True, studies=True) -> PeriodicReport:
    """Analyse a periodic case for its report (module docstring)."""
    a = periodic_analysis(spec, config=config)
    times, lam = frozen_time(a)
    chk = check_floquet(a, amplitude=1e-5, periods=8, rtol=1e-3) if run_check else None
    runs = ()
    if studies:
        declared = (getattr(a.timed.base, "report", None) or {}).get("studies", [])
        runs = tuple(_study(spec, st.get("config", config), st) for st in declared
                     if st.get("config") in (None, config))
    model = a.timed.base
    fl = floquet_json(a)
    T = float(fl["period"])
    ebounds = tuple(float(b) / (abs(complex(*m)) * T) if abs(complex(*m)) > 0 else math.inf
                    for m, b in zip(fl["multipliers"], fl["error_bounds"], strict=True))
    frozen = frozen_summary(a)
    return PeriodicReport(spec.name, str(spec.data.get("title", "")),
                          getattr(model, "description", "") or "", config, a, fl,
                          frozen, times, lam, chk, runs, ebounds, frozen["bound"])
