"""``mbseig modes CASE`` on a periodic case (DESIGN §8, "Periodic motions"): the reference
motion, the Floquet multipliers with their error bounds and the verdict; the frozen-time
eigenvalues are listed beside them as what a frozen-time analysis would (wrongly) conclude."""

from __future__ import annotations

import math

from ..studies.periodic import floquet_json, frozen_summary, periodic_analysis
from .common import analyzed, print_json


def exponent_modes(fl) -> list:
    """The Floquet exponents s = ln(μ)/T listed as modes (imaginary part reduced modulo 2π/T,
    a conjugate pair once with im > 0), each with the stability of its multiplier: stable when
    |μ| + b < 1, unstable when |μ| − b > 1, critical otherwise (b its error bound); the
    ``backward_error`` field holds b/|μ|.  Sorted by omega_n, then delta."""
    rows = []
    for mu, ex, b in zip(fl["multipliers"], fl["exponents"], fl["error_bounds"]):
        re, im = ex
        if im < 0 or (im == 0 and mu[1] < 0):
            continue  # the conjugate of a listed pair
        m = abs(complex(*mu))
        stability = "unstable" if m - b > 1 else "stable" if m + b < 1 else "critical"
        wn = math.hypot(re, im)
        if im == 0:
            kind = "divergence" if stability == "unstable" else "overdamped" if re < 0 else "rigid-body"
        else:
            kind = "flutter" if stability == "unstable" else "oscillatory"
        rows.append({"eigenvalue": [re, im], "delta": -re, "omega_n": wn, "omega_d": abs(im),
                     "freq_hz": abs(im) / (2 * math.pi), "zeta": -re / wn if wn else 0.0,
                     "stability": stability, "kind": kind, "multiplier": mu,
                     "backward_error": b / m if m else b})
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
        "modes": exponent_modes(fl),
        "floquet": fl,
        "frozen_time": frozen_summary(a),
    }


def run(args, spec) -> int:
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
    print(f"{'k':>3} {'multiplier':>30} {'|mu|':>12} {'bound':>9} {'exponent':>28}")
    for k, (mu, ex, b) in enumerate(zip(fl["multipliers"], fl["exponents"], fl["error_bounds"])):
        print(f"{k + 1:>3} {mu[0]:>14.8g} {mu[1]:+14.8g}j {abs(complex(*mu)):>12.8g} {b:>9.1e} "
              f"{ex[0]:>13.6g} {ex[1]:+13.6g}j")
    d = fl["decided_by"]
    print(f"verdict: {fl['verdict']} (multiplier {d['index'] + 1}: |mu| = {d['modulus']:.10g} "
          f"± {d['bound']:.1e}, margin {d['margin']:.3g})")
    fz = out["frozen_time"]
    print(f"frozen-time eigenvalues ({fz['instants']} instants): max Re s = "
          f"{fz['max_real_part']:.4g}, would say {fz['verdict']} (not a criterion here)")
    return 0
