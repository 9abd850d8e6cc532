"""``mbseig check CASE`` on a steady motion (DESIGN §8): the nonlinear model, non-holonomic rows
included, simulated from the reference motion perturbed along each mode; δ and ω measured against
the prediction (:mod:`mbseig.studies.steady_check`).  Exit 0 when every simulated mode passes,
1 when one fails."""

from __future__ import annotations

import math

from ..check.modes import parse_mode_list
from ..errors import CaseError
from .common import case_kwargs, number_option, print_json

__all__ = ["run"]


def run(args, spec) -> int:
    from ..studies.steady_check import check_steady
    from ..studies.steady_modes import analyze_steady

    if getattr(args, "method", "DOP853") != "DOP853":
        raise CaseError("a steady motion is checked with DOP853 only", element="command line")
    if getattr(args, "plot", None):
        raise CaseError("--plot is not available for a steady motion", element="command line")
    if getattr(args, "solver", "auto") != "auto":
        raise CaseError("a steady motion's linearization is solved by descriptor-qz (--solver "
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
