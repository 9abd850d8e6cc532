"""A row of "Stability where methods fail" for steady motions: the naive linearization of a
rolling constraint (its position derivative at the reference velocities dropped) shown wrong.

The rolling disk (m = r = g = 1, uniform thin disk) at its critical speed v² = g r/3: the exact
linearization has only s = 0 (the lean pair s² = −4(3v² − g r)/(5r²) passes through zero there;
closed form, cases/rolling_disk.toml).  Dropping ∂(A(q) q̇₀)/∂q removes the centripetal force of
the heading rate, m v ψ̇, from the lean equation: s² = −[I_a² v²/(I_t r²) − m g r]/(I_t + m r²)
= 8/15, a spurious real pair ±0.7303 (a divergence) in mbseig's natural-coordinate form.  Which
spurious value appears depends on which term a formulation drops (sympy's Kane linearizer
dropping the differentiated constraints gives ±0.4714i on the same disk); none is right.  The
time-domain check (:func:`mbseig.studies.steady_check.check_steady`) simulates the nonlinear
model along the naive mode and measures a δ far from the prediction: the check fails it.
"""

from __future__ import annotations

import math

import numpy as np

from .cases import case_path
from .failrecord import FailCase

__all__ = ["ALL_STEADY", "rolling_disk_naive", "run_steady"]

PARAMS = {"g": "1", "m": "1", "r": "1", "v": "sqrt(1/3)"}


def rolling_disk_naive(*, efolds=1.0):
    from ..studies.pipeline import as_spec
    from ..studies.steady_check import check_steady
    from ..studies.steady_modes import analyze_steady

    spec = as_spec(case_path("rolling_disk"))
    exact = analyze_steady(spec, params=PARAMS)
    naive = analyze_steady(spec, params=PARAMS, naive=True)
    big = [r for r in naive.modes if r["kind"] != "rigid-body"]
    s_naive = max((complex(*r["eigenvalue"]) for r in big), key=lambda s: s.real, default=0j)
    exact_big = max((abs(complex(*r["eigenvalue"])) for r in exact.modes
                     if r["kind"] != "rigid-body"), default=0.0)
    chk = check_steady(spec, params=PARAMS, naive=True, efolds=efolds)
    sim = [m for m in chk.modes if not m.skipped]
    grow = next((m for m in sim if m.predicted_delta < 0), None)
    ref = math.sqrt(8.0 / 15.0)
    measured = (f"; the check measures δ = {grow.measured_delta:+.3g} (predicted "
                f"{grow.predicted_delta:+.4g}): {'passed' if grow.passed else 'FAILED'}"
                if grow is not None else "")
    return FailCase(
        "rolling disk at v² = g r/3: velocity-constraint terms",
        "linearize without ∂(A q̇₀)/∂q",
        f"s = ±{abs(s_naive):.4g} ({big[0]['kind'] if big else 'none'}, "
        f"{naive.verdict}){measured}",
        f"{sum(r['kind'] == 'rigid-body' for r in exact.modes)} × s = 0 "
        f"(largest other |s| = {exact_big:.2g}), {exact.verdict}",
        "s = 0 only: the lean pair s² = −4(3v² − g r)/(5r²) vanishes at v² = g r/3 "
        "(closed form of the linearized equations)",
        naive_wrong=bool(abs(abs(s_naive) - ref) < 1e-8 and grow is not None and not grow.passed),
        mbseig_right=bool(exact_big < 1e-4),
        data={"s_naive": [float(s_naive.real), float(s_naive.imag)],
              "s_naive_closed_form": ref,
              "measured_delta": None if grow is None else float(grow.measured_delta),
              "measured_omega": None if grow is None else float(grow.measured_omega),
              "check_passed": None if grow is None else bool(grow.passed),
              "exact_max_abs": float(exact_big),
              "exact_rigid": int(sum(r["kind"] == "rigid-body" for r in exact.modes)),
              "naive_eigenvalues": [[float(np.real(complex(*r["eigenvalue"]))),
                                     float(np.imag(complex(*r["eigenvalue"])))] for r in big]})


ALL_STEADY = [rolling_disk_naive]


def run_steady():
    return [f() for f in ALL_STEADY]
