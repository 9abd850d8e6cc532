"""The modes of a steady motion (DESIGN §8): the case built, its ``[motion]`` read, the steady
state solved (:func:`mbseig.studies.steady.steady_state`), the first-order descriptor system
linearized (:func:`~mbseig.studies.steady.linearize_steady`) and solved by the ``descriptor``
eigensolver family (:mod:`mbseig.eigen.descriptor`) with the same measures as the quadratic
paths; the classification follows mbseig's rule (docs/design.md, "Modes"):

    tolerance  τ = SAFETY · κ η · max(|s|, 1)      (κη: first-order error bound of s)
    stable: δ = −Re s > τ;  unstable: δ < −τ;  critical: |δ| ≤ τ

so a tolerance never turns an eigenvalue whose real part is positive beyond its own error bound
into "critical".  The exact s = 0 of the cyclic coordinates (position along the motion,
heading in straight running) is deflated structurally (:func:`mbseig.eigen.descriptor.deflate_zero`)
and listed as rigid-body, critical.  Its rank tolerance ``ZERO_TOL`` = 1e-15 relative to ‖A‖₂:
the cyclic zeros are null vectors of A at rounding level (singular values ≤ 1e-16 ‖A‖₂ in the
bundled cases), while a real eigenvalue passing through zero (the bicycle's capsize) is deflated
only within |s| ≲ 1e-15 ‖A‖₂ of it, which keeps a sweep's divergence boundary continuous to
~1e-11 in the speed.  A cyclic zero the tolerance missed stays in the list as a tiny eigenvalue
classified rigid-body by its own tolerance (|s| ≤ τ).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import CaseError

__all__ = ["SAFETY", "ZERO_TOL", "SteadyAnalysis", "analyze_steady", "mode_rows", "steady_json"]

SAFETY = 10.0  # τ = SAFETY·κη·max(|s|, 1): mbseig's safety factor on the error bound
ZERO_TOL = 1e-15  # rank tolerance of the cyclic zero deflation, relative to ‖A‖₂ (module docstring)


@dataclass(frozen=True, eq=False)
class SteadyAnalysis:
    """One steady motion analysed: model, motion, state, linearization, solution and the mode
    rows (dicts with the fields of ``modes --json``), with the verdict and notes."""

    model: object
    motion: object
    state: object
    linear: object
    solution: object
    modes: tuple
    verdict: str
    notes: tuple


def mode_rows(sol, *, safety=SAFETY) -> list:
    """Mode records as the quadratic paths list them: δ = −Re s, a pair once (Im s > 0), sorted
    by ω_n then δ, with η, κ and the tolerance τ (module docstring)."""
    n_rigid = int(sol.details.get("n_rigid", 0))
    rows = [{"eigenvalue": [0.0, 0.0], "delta": 0.0, "omega_n": 0.0, "omega_d": 0.0,
             "freq_hz": 0.0, "freq_n_hz": 0.0, "zeta": 0.0, "stability": "critical",
             "kind": "rigid-body", "backward_error": 0.0, "condition": 1.0, "tolerance": 0.0}
            for _ in range(n_rigid)]
    eps = np.finfo(float).eps
    for s, eta, kap in zip(sol.eigenvalues, sol.backward_error, sol.condition):
        tol = safety * kap * max(eta, eps) * max(abs(s), 1.0)
        if s.imag < -tol:
            continue  # the conjugate of a listed pair
        wd = float(s.imag) if s.imag > tol else 0.0
        delta = -float(s.real)
        wn = float(abs(s))
        stab = "stable" if delta > tol else "unstable" if delta < -tol else "critical"
        kind = ("rigid-body" if wn <= tol else
                ("overdamped" if delta > 0 else "divergence") if wd == 0.0 else
                ("flutter" if stab == "unstable" else "oscillatory"))
        rows.append({"eigenvalue": [float(s.real), wd], "delta": delta, "omega_n": wn,
                     "omega_d": wd, "freq_hz": wd / (2 * math.pi),
                     "freq_n_hz": wn / (2 * math.pi),
                     "zeta": delta / wn if wn > 0 and kind != "rigid-body" else 0.0,
                     "stability": stab, "kind": kind, "backward_error": float(eta),
                     "condition": float(kap), "tolerance": float(tol)})
    rows.sort(key=lambda r: (r["omega_n"], r["delta"]))
    for k, r in enumerate(rows):
        r["index"] = k + 1
    return rows


def dominant(model, lin, s, *, count=3) -> list:
    """The mode shape of eigenvalue ``s`` in the full coordinates, q − q₀(t) = N x (x: the
    position part of the right null vector of s E − A): the ``count`` coordinates that move
    most, as [name, |component| / largest] (the shape of a moving system, in the frame moving
    with the reference)."""
    _, _, Vh = np.linalg.svd(s * lin.E - lin.A)
    shape = np.abs(lin.N @ Vh[-1].conj()[:lin.dof])
    top = float(shape.max(initial=0.0))
    if top == 0.0:
        return []
    order = np.argsort(-shape)[:count]
    return [[model.coordinate_names[i], float(shape[i] / top)] for i in order]


def verdict_of(rows) -> str:
    order = {"stable": 0, "critical": 1, "unstable": 2}
    return max((r["stability"] for r in rows), key=order.get, default="stable")


def analyze_steady(spec, *, config=None, params=None, naive=False, model=None):
    """The steady motion of the case ``spec`` (a :class:`~mbseig.casefile.CaseSpec`) at
    ``params``.  ``naive=True`` drops the velocity rows' position derivative (shown wrong in
    tests and in ``mbseig bench``; never used by the commands)."""
    from ..casefile.motion_readers import read_motion
    from ..eigen import Request, descriptor_problem, solve
    from ..errors import MbseigError
    from ..model.contact import PointContact
    from .steady import SteadyMotionError, linearize_steady, steady_state

    if model is None:
        model = spec.build(config, **(params or {}))
    file = getattr(spec, "source", None)
    motion = read_motion(spec.data, dict(model.parameters), file=file)
    if any(isinstance(c, PointContact) for c in model.constraints):
        raise CaseError("point contacts in a steady motion are not analysed (a rolling joint "
                        "is the contact of a moving wheel)", element="motion", file=file)
    from ..numerics import DOUBLE_RANGE, watched

    cause = f"values of the case too large or too small together (beyond {DOUBLE_RANGE})"
    try:
        with watched("steady motion", cause):
            state = steady_state(model, motion)
            lin = linearize_steady(model, state, naive=naive)
            sol = solve(descriptor_problem(lin.E, lin.A),
                        Request(solver="descriptor-qz", options={"zero_tol": ZERO_TOL}))
    except MbseigError as exc:
        raise exc.located(file=file) from None
    except (np.linalg.LinAlgError, ValueError) as exc:  # a solve that did not converge
        raise SteadyMotionError(f"the steady motion could not be linearized ({exc})",
                                file=file) from None
    notes = tuple(f"wheel {c['name']!r} would pull ({c['force']:.6g} N): the steady motion "
                  f"lifts it off the plane" for c in state.contacts if not c["active"])
    rows = mode_rows(sol)
    for r in rows:
        if r["kind"] != "rigid-body":
            r["dominant"] = dominant(model, lin, complex(*r["eigenvalue"]))
    return SteadyAnalysis(model, motion, state, lin, sol, tuple(rows), verdict_of(rows), notes)


def steady_json(a: SteadyAnalysis) -> dict:
    """The ``mbseig modes --json`` object of a steady motion (DESIGN §8: ``motion``,
    ``contacts``; extra keys only extend the fixed object)."""
    model, st, lin, sol = a.model, a.state, a.linear, a.solution
    n_vel = 2 * len(st.spin)
    return {
        "case": model.name,
        "parameters": dict(model.parameters),
        "n_coordinates": int(model.n),
        "n_constraints": int(model.n_constraints),
        "n_velocity_constraints": n_vel,
        "n_redundant": int(model.n - lin.dof - model.n_constraints),
        "dof": int(lin.dof),
        "n_velocities": int(lin.n_velocities),
        "solver": sol.solver,
        "solver_reason": "velocity constraints: first-order descriptor pencil E X' = A X, "
                         "X = [positions; independent velocities]",
        "equilibrium": {"residual": float(st.residual), "iterations": int(st.iterations),
                        "notes": list(a.notes)},
        "motion": {"speed": float(a.motion.speed), "direction": list(a.motion.direction),
                   "yaw_rate": float(a.motion.yaw_rate)},
        "contacts": [dict(c) for c in st.contacts],
        "spins": [float(x) for x in st.spin],
        "verdict": a.verdict,
        "n_infinite": int(sol.n_infinite),
        "n_rigid_deflated": int(sol.details.get("n_rigid", 0)),
        "tolerances": {"safety": SAFETY, "zero_tol": ZERO_TOL,
                       "inf_tol": float(sol.details.get("inf_tol", 0.0)),
                       "rank_tol": float(lin.tolerances.get("rank_tol", 0.0))},
        "modes": [dict(r) for r in a.modes],
    }
