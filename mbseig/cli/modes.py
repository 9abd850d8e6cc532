"""``mbseig modes CASE``: the modes, their stability and the verdict."""

from __future__ import annotations

from .common import analyzed

import math

import numpy as np

from ..display import fmt, fmt_complex, shown

from ..eigen import SOLVERS
from ..errors import CaseError, MbseigError
from ..statics.reactions import reaction_forces
from ..studies import analyze, modes_json
from ..studies.mesh_rounding import mesh_rounding
from .common import (
    add_case_arguments,
    case_kwargs,
    equilibrium_notes,
    case_command,
    number_option,
    print_json,
    print_reactions,
)


def register(sub):
    p = sub.add_parser("modes", help="solve the modes and classify their stability")
    add_case_arguments(p)
    p.add_argument("--solver", default="auto", choices=["auto", *SOLVERS],
                   help="eigensolver path (default: chosen by structure)")
    p.add_argument("--n-modes", type=int, default=None, metavar="K",
                   help="only the K modes nearest the target (sparse shift-invert path, "
                        "large models)")
    p.add_argument("--floquet", choices=("auto", "full", "partial"), default="auto",
                   help="a periodic case with --n-modes K: the K largest |mu| from the full "
                        "monodromy (full), by the partial (Arnoldi) method (partial), or (auto) "
                        "by the partial method from 100 DOF on within a product budget, else "
                        "the full monodromy")
    p.add_argument("--target-hz", type=float, default=None, metavar="F",
                   help="with --n-modes: the modes whose natural frequency omega_n/2pi = "
                        "|s|/2pi is nearest F Hz (default 0: the lowest)")
    p.add_argument("--band-hz", type=float, nargs=2, default=None, metavar=("F1", "F2"),
                   help="every mode with natural frequency F1 <= omega_n/2pi = |s|/2pi <= F2 "
                        "(small models: the dense solve, listed in the band; large ones: the "
                        "sparse shift-invert path)")
    p.add_argument("--refine-modes", type=int, default=None, metavar="K",
                   help='refine elements = "auto" beams until the lowest K modes converge')
    p.add_argument("--refine-fmax", type=float, default=None, metavar="HZ",
                   help='refine elements = "auto" beams until the modes below HZ converge')
    p.add_argument("--accuracy", type=float, default=None, metavar="A",
                   help="relative accuracy of the refined modes (default: the case's, else 1e-3)")
    p.add_argument("--sensitivities", action="store_true",
                   help="each mode's eigenvalue derivative ds/dp for every real parameter of "
                        "[parameters] that enters the model")
    p.add_argument("--energy", action="store_true",
                   help="each mode's kinetic and potential energy shares (bodies and masses; "
                        "springs, torsional elements, constraints, gravity)")
    p.add_argument("--reactions", action="store_true",
                   help="also print the joint reactions at equilibrium (multipliers, what they "
                        "carry, forces on the points)")
    p.set_defaults(run=run)


def _partial_options(args) -> dict:
    opts = {}
    if args.n_modes is not None:
        if args.n_modes < 1:
            raise CaseError(f"--n-modes must be a positive integer, got {args.n_modes}",
                            element="command line")
        opts["n_modes"] = args.n_modes
    if args.target_hz is not None:
        opts["target"] = 2 * math.pi * number_option("--target-hz", args.target_hz,
                                                      nonnegative=True)
    if args.band_hz is not None:
        lo, hi = (number_option("--band-hz", f, nonnegative=True) for f in args.band_hz)
        if not lo < hi:
            raise CaseError(f"--band-hz needs F1 < F2, got {lo:g} {hi:g}", element="command line")
        opts["band"] = (2 * math.pi * lo, 2 * math.pi * hi)
    return opts


def _refine_request(args):
    """{"modes", "f_max", "accuracy"} from --refine-modes/--refine-fmax/--accuracy, or None."""
    if args.refine_modes is None and args.refine_fmax is None:
        if args.accuracy is None:
            return None
    if args.refine_modes is not None and args.refine_modes < 1:
        raise CaseError(f"--refine-modes must be a positive integer, got {args.refine_modes}",
                        element="command line")
    number_option("--refine-fmax", args.refine_fmax, positive=True)
    number_option("--accuracy", args.accuracy, positive=True)
    return {"modes": args.refine_modes, "f_max": args.refine_fmax, "accuracy": args.accuracy}


def _print_flexible(a):
    bodies = (a.model.flexible or {}).get("bodies") or {}
    ref = a.refinement
    for nm, r in bodies.items():
        if r.get("type") != "beam":
            print(f"FE body {nm}: {r['size']} coordinates, interface {', '.join(r['interface'])}")
            continue
        line = (f"beam {nm}: {r['theory']}, slenderness L/d = {r['slenderness']:.4g}, "
                f"{r['elements']} elements")
        if ref is not None and nm in ref.beams:
            b = ref.beams[nm]
            err = b["estimated_error"]
            line += (f" (refined: estimated error {err:.2g}" if err is not None else " (refined")
            line += ")" if b["converged"] else ", NOT converged)"
        print(line)
        for w in r.get("warnings", ()):
            print(f"  warning: {w}")
    rounding = mesh_rounding(a.model, a.linear, a.modes) if bodies else None
    if rounding is not None and not rounding.resolved:
        print(rounding.line())
    if ref is not None:
        what = f"lowest {ref.modes}" if ref.modes else ""
        if ref.f_max:
            what += (" and " if what else "") + f"below {ref.f_max:g} Hz"
        print(f"refinement: modes {what} to {ref.accuracy:g}; estimated error "
              f"{ref.estimated_error:.2g} after {ref.solves} solves")


def _design(args, spec, a):
    """(sensitivities, energies) asked for by --sensitivities / --energy (None when not)."""
    if not (args.sensitivities or args.energy):
        return None, None
    from ..studies.design import eigen_sensitivities, modal_energy

    kw = case_kwargs(args)
    try:
        sens = eigen_sensitivities(spec, config=kw["config"], params=kw["params"],
                                   analysis=a, with_bounds=True) if args.sensitivities else None
        energy = modal_energy(a.model, a.eq, a.linear, a.modes) if args.energy else None
    except MbseigError as exc:
        raise exc.located(file=a.model.source) from None
    return sens, energy


def _no_floquet(args, spec, what):
    """--floquet chooses how a periodic case answers --n-modes: refused elsewhere."""
    if getattr(args, "floquet", "auto") != "auto":
        raise CaseError(f"--floquet applies to a periodic case with --n-modes K, not to {what}",
                        element="command line", file=spec.source)


def run_rest(args, spec) -> int:
    _no_floquet(args, spec, "a case at rest")
    a = analyze(spec, solver=args.solver, modes_options=_partial_options(args) or None,
                refine=_refine_request(args), **case_kwargs(args))
    sens, energy = _design(args, spec, a)
    if args.json:
        out = modes_json(a)
        for k, mode in enumerate(out["modes"]):
            if sens is not None:
                mode["sensitivity"] = {p: [float(v[k].real), float(v[k].imag)]
                                       for p, v in sens[0].items()}
                mode["sensitivity_bound"] = {p: float(b[k]) for p, b in sens[1].items()}
            if energy is not None:
                mode["energy"] = energy[k]
        if args.reactions:
            out["reactions"] = reaction_forces(a.model, a.eq)
        print_json(out)
        return 0
    m, eq, lin = a.model, a.eq, a.linear
    n_c = m.n_constraints
    print(f"case {m.name}: {m.n} coordinates, {n_c} constraints ({eq.n_redundant} redundant), "
          f"{lin.dof} DOF")
    if eq.redundant:
        print("redundant: " + "; ".join(eq.redundant))
    print(f"equilibrium: residual {eq.residual:.2e} after {eq.iterations} Newton iterations")
    for note in equilibrium_notes(eq):
        print(f"equilibrium note: {note}")
    print(f"solver: {a.modes.solver} ({a.modes.solver_reason})")
    _print_flexible(a)
    print(a.modes.table())
    print(f"verdict: {a.modes.verdict}")
    for k in range(len(a.modes)):
        if sens and sens[0]:  # the zero rule on each ∂s/∂p with its propagated bound
            print(f"mode {k + 1} ds/dp: " + "; ".join(
                f"{p} {fmt_complex(v[k], b[k], b[k], '.4g')}"
                for (p, v), b in zip(sens[0].items(), sens[1].values(), strict=True)))
        if energy is not None:
            for kind in ("kinetic", "potential"):
                parts = energy[k][kind]
                # a share is a part over the total, each summed in floating point: it errs by
                # at most 64 ε Σ|share| (Σ|parts| / |total|)
                bound = 64 * np.finfo(float).eps * sum(abs(v) for v in parts.values())
                shares = sorted(parts.items(), key=lambda t: -abs(t[1]))
                print(f"mode {k + 1} {kind} energy: " + (", ".join(
                    f"{nm} {shown(v, bound):.1%}" for nm, v in shares) or "none"))
    if args.reactions:
        print_reactions(reaction_forces(a.model, eq))
    return 0


# ---- steady motion (steady reference: [motion] with speed)
# ``mbseig modes CASE`` on a steady motion (DESIGN §8, ``[motion]`` with ``speed``): the steady
# state, its contact forces and the modes of the first-order descriptor system
# (:mod:`mbseig.studies.steady_modes`).
# options of the static command that a steady motion does not take (refused, never ignored)
_STATIC_ONLY = ("n_modes", "target_hz", "band_hz", "refine_modes", "refine_fmax", "accuracy")


def run_steady(args, spec) -> int:
    from ..studies.steady_modes import analyze_steady, steady_json

    _no_floquet(args, spec, "a steady motion")
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
                        f"linearization is a first-order pencil: auto, the path of a steady "
                        f"sweep, or descriptor-qz)", element="command line")
    kw = case_kwargs(args)
    a = analyze_steady(spec, config=kw["config"], params=kw["params"],
                       solver=getattr(args, "solver", "auto"))
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


# ---- periodic motion (periodic reference: [motion] with period)
# ``mbseig modes CASE`` on a periodic case (DESIGN §8, "Periodic motions"): the reference
# motion, the Floquet multipliers with their error bounds and the verdict; the frozen-time
# eigenvalues are listed beside them as what a frozen-time analysis would (wrongly) conclude.
#
# ``--n-modes K``: the K multipliers of largest modulus.  ``full`` takes them from the full
# monodromy, ``partial`` runs Arnoldi on the monodromy operator without forming the monodromy
# matrix, ``auto`` (the default) tries the partial method within a product budget from 100 DOF
# on and otherwise answers from the full monodromy
# (:func:`mbseig.studies.periodic_partial.largest_multipliers`).  The frozen-time summary is left
# out (it needs every eigenvalue at 64 instants).
def _run_largest(args, spec) -> int:
    if args.band_hz is not None or args.target_hz is not None:
        raise CaseError("--target-hz and --band-hz select eigenvalues of a static case; a "
                        "periodic case takes --n-modes K (the K largest |mu|)",
                        element="command line", file=spec.source)
    from ..studies.periodic_partial import largest_multipliers

    kw = case_kwargs(args)
    out = largest_multipliers(spec, k=args.n_modes, floquet=args.floquet, config=kw["config"],
                              params=kw["params"])
    of = out["floquet"]["selected"]["of"]
    if args.json:
        return print_json(out)
    fl = out["floquet"]
    print(f"case {out['case']}: periodic, T = {fl['period']:.6g} s, {out['n_coordinates']} "
          f"coordinates, {out['n_constraints']} constraints, {out['dof']} DOF")
    print(f"solver: {out['solver']}")
    if "selected" in fl:
        print(f"method: {fl['selected']['method']}")
    print(f"the {len(fl['multipliers'])} largest of {of} multipliers:")
    _table(fl)
    return 0


def _table(fl):
    print(f"{'k':>3} {'multiplier':>30} {'|mu|':>12} {'bound':>9} {'exponent':>28}")
    T = float(fl["period"])
    for k, (mu, ex, b) in enumerate(zip(fl["multipliers"], fl["exponents"], fl["error_bounds"],
                                        strict=True)):
        m = abs(complex(*mu))
        be = b / (m * T) if m else b  # the exponent's bound, to first order
        # the zero rule (mbseig.display): a part within its bound of 0 reads 0
        print(f"{k + 1:>3} {fmt(mu[0], b, '.8g'):>14} {fmt(mu[1], b, '+.8g'):>14}j {m:>12.8g} "
              f"{b:>9.1e} {fmt(ex[0], be, '.6g'):>13} {fmt(ex[1], be, '+.6g'):>13}j")
    d = fl["decided_by"]
    print(f"verdict: {fl['verdict']} (multiplier {d['index'] + 1}: |mu| = {d['modulus']:.10g} "
          f"± {d['bound']:.1e}, margin {d['margin']:.3g})")


def run_periodic(args, spec) -> int:
    if getattr(args, "n_modes", None) is not None:
        if args.n_modes < 1:
            raise CaseError(f"--n-modes must be a positive integer, got {args.n_modes}",
                            element="command line", file=spec.source)
        return _run_largest(args, spec)
    if getattr(args, "floquet", "auto") != "auto":
        raise CaseError("--floquet chooses how --n-modes K is answered (the K largest |mu|); "
                        "without --n-modes every multiplier comes from the full monodromy",
                        element="command line", file=spec.source)
    from ..studies.periodic import periodic_analysis
    from ..studies.periodic_listing import periodic_json

    a = analyzed(args, spec, periodic_analysis)
    out = periodic_json(a)
    if args.json:
        return print_json(out)
    fl, ref = out["floquet"], a.reference
    print(f"case {out['case']}: periodic, T = {fl['period']:.6g} s, {out['n_coordinates']} "
          f"coordinates, {out['n_constraints']} constraints, {out['dof']} DOF")
    print(f"reference motion: {ref.method}; residual {ref.residual:.2e} after {ref.iterations} "
          "iterations")
    print(f"solver: {a.floquet.method}; Liouville check {fl['det_check']:.1e}")
    _table(fl)
    fz = out["frozen_time"]
    print(f"frozen-time eigenvalues ({fz['instants']} instants): max Re s = "
          f"{fz['max_real_part']:.4g}, would say {fz['verdict']} (not a criterion here)")
    return 0


#: the command on every reference the case declares (its [motion] table)
run = case_command("modes", rest=run_rest, steady=run_steady, periodic=run_periodic)
