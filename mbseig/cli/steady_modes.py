"""``mbseig modes CASE`` on a steady motion (DESIGN §8, ``[motion]`` with ``speed``): the steady
state, its contact forces and the modes of the first-order descriptor system
(:mod:`mbseig.studies.steady_modes`)."""

from __future__ import annotations

import math

from ..display import fmt, shown
from ..errors import CaseError
from .common import analyzed, print_json

__all__ = ["run"]

# options of the static command that a steady motion does not take (refused, never ignored)
_STATIC_ONLY = ("n_modes", "target_hz", "band_hz", "refine_modes", "refine_fmax", "accuracy")


def run(args, spec) -> int:
    from ..studies.steady_modes import analyze_steady, steady_json

    for opt in _STATIC_ONLY:
        if getattr(args, opt, None) is not None:
            raise CaseError(f"--{opt.replace('_', '-')} does not apply to a steady motion "
                            f"(all modes of the descriptor pencil are solved)",
                            element="command line")
    for opt in ("sensitivities", "energy", "reactions"):
        if getattr(args, opt, False):
            raise CaseError(f"--{opt} is not available for a steady motion",
                            element="command line")
    if getattr(args, "solver", "auto") not in ("auto", "descriptor-qz"):
        raise CaseError(f"solver {args.solver!r} does not apply to a steady motion (its "
                        f"linearization is a first-order pencil: descriptor-qz)",
                        element="command line")
    a = analyzed(args, spec, analyze_steady)
    out = steady_json(a)
    if args.json:
        return print_json(out)
    m = out["motion"]
    print(f"case {out['case']}: steady motion at {m['speed']:g} m/s along "
          f"{motion_direction(m['direction'])}"
          + (f", yaw rate {m['yaw_rate']:g} rad/s" if m["yaw_rate"] else "")
          + f"; {out['n_coordinates']} coordinates, {out['n_constraints']} holonomic and "
          f"{out['n_velocity_constraints']} velocity constraints, {out['dof']} positions, "
          f"{out['n_velocities']} independent velocities")
    print(f"steady state: residual {out['equilibrium']['residual']:.3g} after "
          f"{out['equilibrium']['iterations']} iterations")
    for c in out["contacts"]:
        print(f"  contact {c['name']}: normal force {c['force']:.6g} N, "
              f"{'active' if c['active'] else 'RELEASED'}")
    for note in out["equilibrium"]["notes"]:
        print(f"  {note}")
    print(f"verdict: {out['verdict']} ({out['solver']})")
    if out.get("verdict_scope"):
        print(f"verdict scope: {out['verdict_scope']}")
    print(f"{'#':>3} {'Re s':>14} {'Im s':>14} {'f_n [Hz]':>11} {'zeta':>8}  {'kind':<12} "
          f"{'stability':<9} dominant")
    for r in out["modes"]:  # the zero rule: a value within its bound τ of 0 reads 0
        re, im = r["eigenvalue"]
        b = r["tolerance"]
        zeta = 0.0 if shown(re, b) == 0 else r["zeta"]
        what = r.get("rigid_body") or ", ".join(nm for nm, _ in r.get("dominant", []))
        print(f"{r['index']:>3} {fmt(re, b, '.8g'):>14} {fmt(im, b, '.8g'):>14} "
              f"{fmt(r['freq_n_hz'], b / (2 * math.pi), '.6g'):>11} {zeta:>8.4f}  "
              f"{r['kind']:<12} {r['stability']:<9} {what}")
    print("values within their error bound of 0 are printed as 0 (the JSON keeps them)")
    return 0


def motion_direction(d) -> str:
    """A unit direction as a person reads it: 'x', '−y', or '(0.6, 0.8, 0)'."""
    axes = [k for k, c in enumerate(d) if c != 0]
    if len(axes) == 1:
        return ("−" if d[axes[0]] < 0 else "") + "xyz"[axes[0]]
    return "(" + ", ".join(f"{c:.4g}" for c in d) + ")"
