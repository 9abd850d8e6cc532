"""``mbseig modes CASE`` on a steady motion (DESIGN §8, ``[motion]`` with ``speed``): the steady
state, its contact forces and the modes of the first-order descriptor system
(:mod:`mbseig.studies.steady_modes`)."""

from __future__ import annotations

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
    print(f"case {out['case']}: steady motion at {m['speed']:g} along {m['direction']}"
          + (f", yaw rate {m['yaw_rate']:g}" if m["yaw_rate"] else "")
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
    print("  #   Re s            Im s            zeta       kind          stability")
    for r in out["modes"]:
        re, im = r["eigenvalue"]
        print(f"{r['index']:3d}  {re:+.8e}  {im:.8e}  {r['zeta']:+.4f}  {r['kind']:13s} "
              f"{r['stability']}")
    return 0
