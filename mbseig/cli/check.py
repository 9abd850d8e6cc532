"""``mbseig check CASE``: prove each predicted mode against a nonlinear time-domain run.

Exit 0 when every simulated mode passes, 1 when one fails, 2 on bad input.
"""

from __future__ import annotations


import math

import numpy as np

from ..check import INTEGRATORS, check_modes, parse_mode_list
from ..eigen import dense_solvers
from ..errors import CaseError, MbseigError, NumericalError
from ..numerics import DOUBLE_RANGE, watched
from ..statics.reactions import multiplier_error
from ..studies import analyze
from .common import (
    add_case_arguments,
    add_progress_options,
    case_command,
    case_kwargs,
    number_option,
    output_notes,
    print_json,
    print_reactions,
    show_progress,
)

CHECK_CAUSE = (f"the simulation left {DOUBLE_RANGE} (an amplitude too large for the model, or "
               f"values of the case too large or too small together)")
# SciPy's explicit Runge-Kutta methods raise a smaller rtol to 100 machine epsilons with a
# warning: the check refuses such a tolerance instead of running at another one
MIN_ODE_RTOL = 100 * np.finfo(float).eps
# stated limits of a run (README, "Input rules"): beyond them a run would not end (10⁹ periods
# of samples), or a growing mode would leave the double range (e^efolds)
LIMITS = {"periods": 1e4, "efolds": 100.0, "amplitude": 1.0}


def register(sub):
    p = sub.add_parser("check", help="cross-check predicted modes against a nonlinear simulation")
    add_case_arguments(p)
    p.add_argument("--modes", default=None, metavar="LIST",
                   help="mode numbers as in the modes table, e.g. 1,2 or 1-3 (default: all)")
    p.add_argument("--amplitude", type=float, default=1e-4, metavar="EPS",
                   help="initial deviation relative to the model's length scale (default 1e-4)")
    p.add_argument("--periods", type=float, default=20.0, metavar="N",
                   help="run length in periods of the checked mode (default 20)")
    p.add_argument("--efolds", type=float, default=3.0, metavar="E",
                   help="cap of the run length in e-folding times 1/|delta| (default 3)")
    p.add_argument("--delta-rtol", type=float, default=1e-2, metavar="R",
                   help="relative tolerance on delta (default 1e-2)")
    p.add_argument("--omega-rtol", type=float, default=1e-3, metavar="R",
                   help="relative tolerance on omega (default 1e-3)")
    p.add_argument("--zero-delta-tol", type=float, default=1e-5, metavar="Z",
                   help="an undamped mode passes when |measured delta| <= Z |s| (default 1e-5)")
    p.add_argument("--method", default="DOP853", choices=list(INTEGRATORS),
                   help="integrator (default DOP853: explicit, no numerical damping; a model "
                        "with beams runs the exponential integrator in its place, or Radau "
                        "where that does not apply)")
    p.add_argument("--ode-rtol", type=float, default=1e-10, metavar="R",
                   help="integrator relative tolerance (default 1e-10)")
    p.add_argument("--solver", default="auto", choices=["auto", *dense_solvers()],
                   help="eigensolver path for the prediction (default: chosen by structure)")
    p.add_argument("--plot", default=None, metavar="DIR",
                   help="write one PNG per checked mode (response and envelopes) into DIR")
    add_progress_options(p, "a progress bar over the modes")
    p.set_defaults(run=run)


def _options(args):
    # positivity and finiteness of every option are checked by check_modes; here the limits
    if math.isfinite(args.ode_rtol) and args.ode_rtol > 0:
        number_option("--ode-rtol", args.ode_rtol, minimum=MIN_ODE_RTOL)
    for name, limit in LIMITS.items():
        value = getattr(args, name)
        if math.isfinite(value) and value > limit:
            raise CaseError(f"--{name} must be at most {limit:g}, got {value:g}",
                            element="command line")


def _checked(a, args):
    """check_modes between its boundary checks: no overflow inside, finite measurements."""
    indices = None if args.modes is None else parse_mode_list(args.modes, len(a.modes))
    bar = None
    if show_progress(args):
        from ..studies.runners import progress_bar

        bar = progress_bar()
    try:
        with watched("check", CHECK_CAUSE):
            res = check_modes(a.model, a.eq, a.linear, a.modes, indices=indices,
                              amplitude=args.amplitude, periods=args.periods, efolds=args.efolds,
                              delta_rtol=args.delta_rtol, omega_rtol=args.omega_rtol,
                              zero_delta_tol=args.zero_delta_tol, method=args.method,
                              ode_rtol=args.ode_rtol, progress=bar)
        for m in res.modes:
            if not m.skipped and not (math.isfinite(m.measured_delta)
                                      and math.isfinite(m.measured_omega)):
                raise NumericalError(f"mode {m.index}: the measured delta or omega is not finite; "
                                     f"likely cause: {CHECK_CAUSE}", element="check")
    except MbseigError as exc:
        raise exc.located(file=a.model.source) from None
    finally:
        if bar is not None:
            bar.close()
    return res


def run_rest(args, spec) -> int:
    _options(args)
    a = analyze(args.case, solver=args.solver, **case_kwargs(args))
    res = _checked(a, args)
    plots = res.plot(args.plot) if args.plot else []
    if args.json:
        out = res.to_dict()
        out["plots"] = [str(p) for p in plots]
        out["notes"] = output_notes(a.model, a.eq)
        out["reaction_error"] = multiplier_error(a.model, a.eq)
        print_json(out)
        return 0 if res.passed else 1
    tol = res.tolerances
    print(f"case {res.name}: {len(res.modes)} mode(s) checked against the nonlinear model "
          f"({res.integrator}, rtol {tol['ode_rtol']:g}"
          + (f" (asked {tol['ode_rtol_asked']:g}: the floor of a stiff model)"
             if tol.get("ode_rtol_asked", tol["ode_rtol"]) != tol["ode_rtol"] else "")
          + f", amplitude {tol['amplitude']:g} x "
          f"{tol['length_scale']:g})")
    print(f"tolerances: delta {tol['delta_rtol']:g} relative (undamped: |delta| <= "
          f"{tol['zero_delta_tol']:g} |s|), omega {tol['omega_rtol']:g} relative")
    print(res.table())
    sim = [m for m in res.modes if not m.skipped]
    if sim:
        print(f"constraint drift before projection <= {max(m.constraint_drift for m in sim):.1e} "
              f"(relative); largest projection {max(m.max_projection for m in sim):.1e}; "
              f"{sum(m.nfev for m in sim)} force evaluations in {res.elapsed:.2f} s")
    for note in output_notes(a.model, a.eq):
        print(f"note: {note}")
    print_reactions(res.reactions)
    for rec in res.actuators:
        print(f"actuator {rec.get('driver', '?')}: effort {rec.get('effort', float('nan')):.6g} "
              f"{rec.get('effort_unit', '')}".rstrip())
    for p in plots:
        print(f"wrote {p}")
    if res.passed:
        probed = sum(1 for m in res.modes if m.skipped and m.passed is not None)
        print(f"check: passed ({len(sim)} simulated, {probed} rigid-body probed, "
              f"{len(res.modes) - len(sim) - probed} skipped)")
        return 0
    print(f"check: FAILED for mode(s) {', '.join(str(k) for k in res.failed)}")
    return 1


# ---- steady motion (steady reference: [motion] with speed)
# ``mbseig check CASE`` on a steady motion (DESIGN §8): the nonlinear model, non-holonomic rows
# included, simulated from the reference motion perturbed along each mode; δ and ω measured against
# the prediction (:mod:`mbseig.studies.steady_check`).  Exit 0 when every simulated mode passes,
# 1 when one fails.
def run_steady(args, spec) -> int:
    from ..studies.steady_check import check_steady
    from ..studies.steady_modes import analyze_steady

    if getattr(args, "method", "DOP853") != "DOP853":
        raise CaseError("a steady motion is checked with DOP853 only", element="command line")
    if getattr(args, "plot", None):
        raise CaseError("--plot is not available for a steady motion", element="command line")
    if getattr(args, "solver", "auto") != "auto":
        raise CaseError("a steady motion's first-order pencil is solved by its own path (--solver "
                        "does not apply)", element="command line")
    for name in ("amplitude", "periods", "efolds", "delta_rtol", "omega_rtol", "zero_delta_tol",
                 "ode_rtol"):
        value = getattr(args, name)
        number_option(f"--{name.replace('_', '-')}", value, positive=True)
        if not math.isfinite(value):
            raise CaseError(f"--{name.replace('_', '-')} must be finite", element="command line")
    kw = case_kwargs(args)
    indices = None
    if args.modes is not None:
        n = len(analyze_steady(spec, config=kw["config"], params=kw["params"]).modes)
        indices = parse_mode_list(args.modes, n)
    res = check_steady(spec, config=kw["config"], params=kw["params"], indices=indices,
                       amplitude=args.amplitude, periods=args.periods, efolds=args.efolds,
                       delta_rtol=args.delta_rtol, omega_rtol=args.omega_rtol,
                       zero_delta_tol=args.zero_delta_tol, ode_rtol=args.ode_rtol)
    if args.json:
        print_json(res.as_dict())
        return 0 if res.passed else 1
    t = res.tolerances
    print(f"case {res.name}: steady motion, {len(res.modes)} mode(s) checked against the nonlinear "
          f"model with its rolling constraints (DOP853, rtol {t['ode_rtol']:g}, amplitude "
          f"{t['amplitude']:g} x {t['length_scale']:g})")
    print("  #  kind          predicted delta  omega         measured delta   omega         result")
    for m in res.modes:
        if m.skipped:
            print(f"{m.index:3d}  {m.kind:13s} {m.skipped}")
            continue
        print(f"{m.index:3d}  {m.kind:13s} {m.predicted_delta:+.6e}  {m.predicted_omega:.6e}  "
              f"{m.measured_delta:+.6e}  {m.measured_omega:.6e}  "
              f"{'passed' if m.passed else 'FAILED'}")
    simulated = [m for m in res.modes if not m.skipped]
    if simulated:
        print(f"constraint drift <= {max(m.constraint_drift for m in simulated):.1e}, velocity "
              f"rows <= {max(m.velocity_drift for m in simulated):.1e}; {res.elapsed:.2f} s")
    if res.passed:
        print(f"check: passed ({len(simulated)} simulated, "
              f"{len(res.modes) - len(simulated)} rigid-body not simulated)")
        return 0
    print(f"check: FAILED for mode(s) {', '.join(str(k) for k in res.failed)}")
    return 1


# ---- periodic motion (periodic reference: [motion] with period)
# ``mbseig check CASE`` on a periodic case: the nonlinear model perturbed along the Floquet
# vector of the largest multiplier, its growth per period against |μ|
# (:mod:`mbseig.studies.periodic_check`).  Exit 0 when they agree within the tolerance, 1 when
# not.
def run_periodic(args, spec) -> int:
    from ..studies.periodic_check import check_floquet
    from ..studies.periodic import periodic_analysis
    kw = case_kwargs(args)
    amplitude = number_option("--amplitude", args.amplitude, positive=True)
    periods = int(max(2, min(number_option("--periods", args.periods, positive=True), 40)))
    a = periodic_analysis(spec, config=kw["config"], params=kw["params"])
    res = check_floquet(a, amplitude=amplitude, periods=periods,
                        ode_rtol=min(args.ode_rtol, 1e-10))
    if args.json:
        print_json({"case": spec.name, "verdict": a.floquet.verdict,
                    "floquet_check": res.to_dict(), "passed": res.passed})
        return 0 if res.passed else 1
    print(f"case {spec.name}: Floquet multiplier {res.index + 1}, mu = {res.multiplier.real:.8g}"
          f"{res.multiplier.imag:+.8g}j, |mu| = {res.modulus:.10g}")
    print(f"nonlinear simulation along its Floquet vector (amplitude {res.amplitude:.3g}, "
          f"{res.periods} periods): growth per period {res.growth:.10g}, relative error "
          f"{res.relative_error:.2e} (tolerance {res.rtol:g}); off the subspace "
          f"{res.off_subspace:.1e}")
    print("check: passed" if res.passed else "check: FAILED")
    return 0 if res.passed else 1


#: the command on every reference the case declares (its [motion] table)
run = case_command("check", rest=run_rest, steady=run_steady, periodic=run_periodic)
