"""``mbseig modes CASE`` on a periodic case (DESIGN §8, "Periodic motions"): the reference
motion, the Floquet multipliers with their error bounds and the verdict; the frozen-time
eigenvalues are listed beside them as what a frozen-time analysis would (wrongly) conclude.

``--n-modes K``: the K multipliers of largest modulus by the partial method (Arnoldi on the
monodromy operator, :mod:`mbseig.studies.periodic_partial`), without forming the monodromy
matrix; the frozen-time summary is left out (it needs every eigenvalue at 64 instants)."""

from __future__ import annotations

import math

from ..errors import CaseError
from ..modal.rules import kind_of
from ..modal.rules import stability as rule
from ..studies.periodic import floquet_json, frozen_summary, periodic_analysis
from ..display import fmt
from .common import analyzed, case_kwargs, print_json


def exponent_modes(fl, condition=None) -> list:
    """The Floquet exponents s = ln(μ)/T listed as modes (imaginary part reduced modulo 2π/T,
    a conjugate pair once with im > 0), each with the stability of its multiplier: stable when
    |μ| + b < 1, unstable when |μ| − b > 1, critical otherwise (b its error bound); the
    ``backward_error`` field holds b/|μ|, ``tolerance`` the band of δ = −ln|μ|/T that b
    decides, b/(|μ| T) to first order, and ``condition`` the condition number κ of μ where the
    method computes it (the full monodromy; ``condition`` aligned with the multipliers).
    A real negative μ (a response of twice the period) is one multiplier, not half of a
    conjugate pair: its exponent ln|μ|/T + iπ/T is listed once, and its ``multiplier`` has
    imaginary part 0.  Sorted by omega_n, then delta."""
    rows = []
    T = float(fl["period"])
    kappa = [None] * len(fl["multipliers"]) if condition is None else list(condition)
    for mu, ex, b, kap in zip(fl["multipliers"], fl["exponents"], fl["error_bounds"], kappa):
        re, im = ex
        if im < 0 or (im == 0 and mu[1] < 0):
            continue  # the conjugate of a listed pair
        m = abs(complex(*mu))
        stability = rule(1.0 - m, b)  # unstable: |μ| − b > 1, stable: |μ| + b < 1
        wn = math.hypot(re, im)
        # a real multiplier at 1 within its bound (and not past it) is a rigid-body motion
        kind = kind_of(stability, -re, im, 0.0,
                       rigid=im == 0 and re >= 0 and stability != "unstable")
        rows.append({"eigenvalue": [re, im], "delta": -re, "omega_n": wn, "omega_d": abs(im),
                     "freq_hz": abs(im) / (2 * math.pi), "zeta": -re / wn if wn else 0.0,
                     "stability": stability, "kind": kind, "multiplier": mu,
                     "backward_error": b / m if m else b, "tolerance": b / (m * T) if m else b,
                     **({} if kap is None else {"condition": float(kap)})})
    rows.sort(key=lambda r: (r["omega_n"], r["delta"]))
    for k, r in enumerate(rows, 1):
        r["index"] = k
    return rows


def result_json(a) -> dict:
    """The modes JSON of a periodic case: the §8 keys, ``floquet``, and ``modes`` listing the
    Floquet exponents (:func:`exponent_modes`)."""
    model = a.timed.base
    ref = a.reference
    fl = floquet_json(a)
    return {
        "case": model.name,
        "parameters": a.parameters,
        "n_coordinates": model.n,
        "n_constraints": model.n_constraints,
        "n_redundant": 0,
        "dof": a.dof,
        "solver": f"floquet: {a.floquet.method}",
        "equilibrium": {"residual": ref.residual, "iterations": ref.iterations},
        "verdict": a.floquet.verdict,
        "modes": exponent_modes(fl, a.floquet.condition),
        "floquet": fl,
        "frozen_time": frozen_summary(a),
    }


def partial_json(p) -> dict:
    """The modes JSON of ``--n-modes K`` (:func:`mbseig.studies.periodic_partial.periodic_partial`)."""
    lin = p.linearization
    model, ref = lin.timed.base, lin.reference
    fl = p.to_dict()
    return {
        "case": model.name, "parameters": p.parameters, "n_coordinates": model.n,
        "n_constraints": model.n_constraints, "n_redundant": 0, "dof": lin.system.dof,
        "solver": f"floquet (partial): {p.method}",
        "equilibrium": {"residual": ref.residual, "iterations": ref.iterations},
        "verdict": p.verdict, "modes": exponent_modes(fl), "floquet": fl,
    }


def _run_partial(args, spec) -> int:
    from ..studies.periodic_partial import periodic_partial

    if args.band_hz is not None or args.target_hz is not None:
        raise CaseError("--target-hz and --band-hz select eigenvalues of a static case; a "
                        "periodic case takes --n-modes K (the K largest |mu|)",
                        element="command line", file=spec.source)
    kw = case_kwargs(args)
    p = periodic_partial(spec, k=args.n_modes, config=kw["config"], params=kw["params"])
    out = partial_json(p)
    if args.json:
        return print_json(out)
    fl = out["floquet"]
    print(f"case {out['case']}: periodic, T = {fl['period']:.6g} s, {out['n_coordinates']} "
          f"coordinates, {out['n_constraints']} constraints, {out['dof']} DOF")
    print(f"solver: {out['solver']}")
    print(f"the {len(fl['multipliers'])} largest of {fl['partial']['of']} multipliers:")
    _table(fl)
    return 0


def _table(fl):
    print(f"{'k':>3} {'multiplier':>30} {'|mu|':>12} {'bound':>9} {'exponent':>28}")
    T = float(fl["period"])
    for k, (mu, ex, b) in enumerate(zip(fl["multipliers"], fl["exponents"], fl["error_bounds"])):
        m = abs(complex(*mu))
        be = b / (m * T) if m else b  # the exponent's bound, to first order
        # the zero rule (mbseig.display): a part within its bound of 0 reads 0
        print(f"{k + 1:>3} {fmt(mu[0], b, '.8g'):>14} {fmt(mu[1], b, '+.8g'):>14}j {m:>12.8g} "
              f"{b:>9.1e} {fmt(ex[0], be, '.6g'):>13} {fmt(ex[1], be, '+.6g'):>13}j")
    d = fl["decided_by"]
    print(f"verdict: {fl['verdict']} (multiplier {d['index'] + 1}: |mu| = {d['modulus']:.10g} "
          f"± {d['bound']:.1e}, margin {d['margin']:.3g})")


def run(args, spec) -> int:
    if getattr(args, "n_modes", None) is not None:
        if args.n_modes < 1:
            raise CaseError(f"--n-modes must be a positive integer, got {args.n_modes}",
                            element="command line", file=spec.source)
        return _run_partial(args, spec)
    a = analyzed(args, spec, periodic_analysis)
    out = result_json(a)
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
