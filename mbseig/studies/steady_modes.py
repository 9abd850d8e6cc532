"""The modes of a steady motion (DESIGN §8): the case built, its ``[motion]`` read, the steady
state solved (:func:`mbseig.studies.steady.steady_state`), the first-order descriptor system
linearized (:func:`~mbseig.studies.steady.linearize_steady`) and solved by the ``descriptor``
eigensolver family (:mod:`mbseig.eigen.descriptor`) with the same measures as the quadratic
paths; the classification follows mbseig's rule (docs/design.md, "Modes"):

    tolerance  τ = SAFETY · κ max(η, n ε) · max(|s|, 1)   (κη: first-order error bound of s)

η is the backward error of the computed pair against the pencil as formed; n ε (n the model's
coordinates) is the rounding of forming that pencil, whose entries are sums over the n
coordinates (|fl(Σ) − Σ| ≤ γ_n Σ|·|, Higham, Accuracy and Stability, Thm 3.5) before the null-
space projection and the deflation: error the solver's η does not see.  At the bicycle's capsize
speed the capsize eigenvalue is 0 to the digits of the speed, and three OpenBLAS kernels gave
Re s = −6.3e-14, +9.5e-14 and +2.2e-13 against a τ of 6.1e-14 from η alone (κ = 27.5,
48 coordinates): η alone made the verdict depend on the machine.
    stable: δ = −Re s > τ;  unstable: δ < −τ;  critical: |δ| ≤ τ

so a tolerance never turns an eigenvalue whose real part is positive beyond its own error bound
into "critical".

Rigid-body modes by construction (DESIGN §6, :func:`cyclic_directions`): the motion declares its
cyclic directions, the symmetries of a system rolling on a horizontal plane under gravity:

* straight running: position along the motion, lateral position, heading (a turn of the whole
  system about the vertical, with its velocities) and speed along the motion (the same motion
  faster: the velocities and spins scaled), each an exact solution of the linearized equations;
* a steady turn: the heading (the phase along the turn) and the two positions in the ground
  plane (in the turning frame a shifted turn, s = ±i r).

Each is checked to be an invariant subspace of the pencil at the rounding level (A S = E S J,
``INVARIANT_TOL`` relative; a candidate that fails, as the speed of a motion with a speed-
dependent force, is dropped) and removed exactly (:func:`mbseig.eigen.deflate_subspace`): its
eigenvalues are those of J (0, and ±i r in a turn), listed as rigid-body and left out of the
verdict by :mod:`mbseig.modal.scope`.  No eigenvalue is removed for lying near 0: a real
eigenvalue passing through 0 (the bicycle's capsize) stays in the pencil, is classified by its
own bound and decides the verdict as any other.
"""

from __future__ import annotations

import dataclasses
import itertools
from dataclasses import dataclass
from types import SimpleNamespace

import numpy as np

from ..errors import CaseError
from .steady_rows import INVARIANT_TOL, PLANE, SAFETY, Cyclic, mode_rows, verdict_of

__all__ = ["SAFETY", "INVARIANT_TOL", "SteadyAnalysis", "analyze_steady", "cyclic_directions",
           "mode_rows", "steady_json", "mode_shape"]


@dataclass(frozen=True, eq=False)
class SteadyAnalysis:
    """One steady motion analysed: model, motion, state, linearization, solution and the mode
    rows (dicts with the fields of ``modes --json``), with the verdict and notes."""

    #: the reference motion this belongs to (mbseig.studies.reference): a steady motion
    kind = "steady"

    model: object
    motion: object
    state: object
    linear: object
    solution: object
    modes: tuple
    verdict: str
    notes: tuple
    cyclic: object = None  # the declared rigid-body directions (Cyclic)

    @property
    def reference(self):
        """The reference motion: the steady state."""
        return self.state

    def to_json(self) -> dict:
        """The ``mbseig modes --json`` object of a steady motion (:func:`steady_json`)."""
        return steady_json(self)


def dominant(display, lin, s, *, count=3) -> list:
    """The mode shape of eigenvalue ``s`` in the full coordinates, q − q₀(t) = N x (x: the
    position part of the right null vector of s E − A), named in the user's terms
    (:func:`mbseig.model.naming.dominant` over ``display``): the ``count`` rows that move most,
    as [name, size / largest] (the shape of a moving system, in the frame moving with the
    reference)."""
    from ..model.naming import dominant as named

    shape = mode_shape(lin, s)
    return [[nm, v] for nm, v in named(display, shape[:, None], count)[0]]


def mode_shape(lin, s):
    """The full-coordinate shape q − q₀(t) = N x of eigenvalue ``s`` (x: the position part of
    the right null vector of s E − A, the right singular vector of its smallest singular
    value)."""
    _, _, Vh = np.linalg.svd(s * lin.E - lin.A)
    return lin.N @ Vh[-1].conj()[:lin.dof]


def cyclic_directions(model, state, lin) -> Cyclic:
    """The declared rigid-body directions of the steady motion ``state`` in the state X of
    ``lin`` (module docstring)."""
    from .steady import generator, translation

    motion = state.motion
    up = np.asarray(motion.up, float)
    up = up / np.linalg.norm(up)
    d = np.asarray(motion.direction, float)
    d = d / np.linalg.norm(d)
    L, ell = generator(model, motion)
    unit = generator(model, dataclasses.replace(motion, yaw_rate=1.0, speed=0.0))[0]
    q0, xi, spin = state.q, state.qd, np.asarray(state.spin, float)
    nw = spin.size
    zero_w = np.zeros(nw)
    cands = []
    turning = abs(float(motion.yaw_rate)) > 0
    lateral = np.cross(up, d)
    t_along, t_side = translation(model, d), translation(model, lateral)
    cands.append((PLANE + " (along the motion)" if turning else "position along the motion",
                  t_along, -L @ t_along, zero_w))
    cands.append((PLANE + " (lateral)" if turning else "lateral position",
                  t_side, -L @ t_side, zero_w))
    h = unit @ q0
    cands.append(("heading" if not turning else "heading (phase along the turn)",
                  h, unit @ xi - L @ h, zero_w))
    if not turning and motion.speed != 0:
        cands.append(("speed along the motion", np.zeros(model.n), ell / motion.speed,
                      spin / motion.speed))
    N, T, S = lin.N, lin.T, lin.S
    scale = max(float(np.linalg.norm(lin.A)), 1e-300)
    vecs, misses = [], []
    for _, dq, dp, dw in cands:  # each candidate in the state X = [x; z]
        x = N.T @ dq
        w = np.concatenate([N.T @ dp, dw])
        z = T.T @ (w + S @ x)
        ref = max(np.linalg.norm(dq), np.linalg.norm(dp), 1.0)
        misses.append(max(np.linalg.norm(N @ x - dq), np.linalg.norm(N @ (N.T @ dp) - dp),
                          np.linalg.norm(T @ z - (w + S @ x))) / ref)
        vecs.append(np.concatenate([x, z]))

    def invariance(keep):  # ‖A Q − E Q J‖/‖A‖ of the span of the candidates kept
        Y = np.column_stack([vecs[k] for k in keep])
        if np.linalg.matrix_rank(Y, tol=1e-9 * np.abs(Y).max()) < len(keep):
            return np.inf
        Q, _ = np.linalg.qr(Y)
        J = np.linalg.lstsq(lin.E @ Q, lin.A @ Q, rcond=None)[0]
        return float(np.linalg.norm(lin.A @ Q - lin.E @ Q @ J)) / scale

    # the largest set of candidates whose span is invariant (a turn's translations are invariant
    # only as a pair), earlier candidates first among sets of one size
    usable = [k for k, m in enumerate(misses) if m <= INVARIANT_TOL]
    keep = ()
    for size in range(len(usable), 0, -1):
        for subset in itertools.combinations(usable, size):
            if invariance(subset) <= INVARIANT_TOL:
                keep = subset
                break
        if keep:
            break
    names = [cands[k][0] for k in keep]
    dropped = [(cands[k][0], float(misses[k]) if k not in usable else invariance((k,)))
               for k in range(len(cands)) if k not in keep]
    if not keep:
        return Cyclic((), np.zeros((lin.E.shape[0], 0)), np.zeros((0, 0)), 0.0, tuple(dropped))
    basis, _ = np.linalg.qr(np.column_stack([vecs[k] for k in keep]))
    from ..eigen import deflate_subspace

    _, _, J, res = deflate_subspace(lin.E, lin.A, basis)
    # the declared eigenvalues (0; ±i r for a turn's plane pair) are those of J: J is
    # nilpotent (straight running) or J (J² + r² I) = 0 (a turn), to the rounding of J
    r = float(motion.yaw_rate)
    Id = np.eye(J.shape[0])
    poly = np.linalg.matrix_power(J, J.shape[0]) if not turning else J @ (J @ J + r * r * Id)
    jn = max(float(np.linalg.norm(J)), abs(r))
    pn = float(np.linalg.norm(poly))
    res = max(res, pn / jn ** (J.shape[0] if not turning else 3) if pn else 0.0)
    return Cyclic(tuple(names), basis, J, res, tuple(dropped), r)


def analyze_steady(spec, *, config=None, params=None, naive=False, model=None, solver="auto"):
    """The steady motion of the case ``spec`` (a :class:`~mbseig.casefile.CaseSpec`) at
    ``params``.  ``naive=True`` drops the velocity rows' position derivative (shown wrong in
    tests and in ``mbseig bench``; never used by the commands).

    ``solver="auto"`` takes the path of a steady sweep with a batch of one
    (:mod:`mbseig.studies.steady_batch`: the same numbers as that sweep's point), and where
    the batch does not cover the motion (its reason: a steady state it does not reach, a set of
    declared directions that needs the subset search, E₂ ill-conditioned, a pair whose vectors
    fail their check) the one-point path below, which ends in QZ; ``"descriptor-qz"`` takes
    that path at once."""
    from ..casefile.motion_readers import read_motion
    from ..eigen import Request, deflate_subspace, descriptor_problem, solve
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
    got = _batch_of_one(model, motion, naive) if solver == "auto" else None
    try:
        with watched("steady motion", cause):
            if got is not None:
                state, lin, cyc, sol = got
            else:
                state = steady_state(model, motion)
                lin = linearize_steady(model, state, naive=naive)
                cyc = cyclic_directions(model, state, lin)
                E2, A2, _, _ = deflate_subspace(lin.E, lin.A, cyc.basis)
                sol = solve(descriptor_problem(E2, A2), Request(solver="descriptor-qz"))
    except MbseigError as exc:
        raise exc.located(file=file) from None
    except (np.linalg.LinAlgError, ValueError) as exc:  # a solve that did not converge
        raise SteadyMotionError(f"the steady motion could not be linearized ({exc})",
                                file=file) from None
    notes = tuple(f"wheel {c['name']!r} would pull ({c['force']:.6g} N): the steady motion "
                  f"lifts it off the plane" for c in state.contacts if not c["active"])
    rows = mode_rows(sol, declared=cyc, formed_in=len(state.q))
    from ..model.naming import display_map

    display = display_map(model, state.q)
    for r in rows:
        if r["kind"] != "rigid-body":
            r["dominant"] = dominant(display, lin, complex(*r["eigenvalue"]))
    return SteadyAnalysis(model, motion, state, lin, sol, tuple(rows), verdict_of(rows), notes,
                          cyc)


def _batch_of_one(model, motion, naive):
    """(state, linearization, declared directions, solution) of the steady sweep's path with a
    batch of one (:meth:`~mbseig.studies.steady_batch.SteadyStack.analyse`), or None where it
    does not cover the motion."""
    from ..eigen.descriptor import GEPSolution
    from ..errors import MbseigError
    from .steady import SteadyLinearization, SteadyState
    from .steady_batch import RANK_TOL, SteadyStack

    stack = SteadyStack(model)
    if stack.reason is not None:
        return None
    try:
        with np.errstate(all="ignore"):  # (a motion whose numbers overflow is not covered)
            r = stack.analyse([motion], naive=naive, full=True)[0]
    except (np.linalg.LinAlgError, ValueError, ArithmeticError, MbseigError):
        return None  # (the one-point path then gives its own, located, error if there is one)
    if not isinstance(r, SimpleNamespace):
        return None
    state = SteadyState(r.q, r.qd, r.spin, r.lam, r.mu, r.residual, r.iterations, r.contacts,
                        motion)
    lin = SteadyLinearization(r.E, r.A, r.N, r.T, r.S, r.dof, r.k, bool(naive), state,
                              {"rank_tol": RANK_TOL})
    o = r.solution
    sol = GEPSolution(o["s"], o["vectors"], o["eta"], o["kappa"], "descriptor-eig",
                      f"E₂ well conditioned (cond₂ {o['cond']:.3g}): eig of E₂⁻¹A₂, η and κ "
                      f"checked (a steady sweep's path, with a batch of one)",
                      n_infinite=0, norms=(float(o["norms"][0]), float(o["norms"][1])),
                      details={"inf_tol": 1e-12, "zero_tol": None, "n_rigid": 0,
                               "e_cond": float(o["cond"])},
                      left_vectors=o["left"], n_dof=r.E2.shape[0], complex_problem=False,
                      problem=(r.E2, r.A2))
    return state, lin, r.cyclic, sol


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
        "verdict_scope": a.verdict.full_scope,
        "n_infinite": int(sol.n_infinite),
        "n_rigid_deflated": len(a.cyclic.names) if a.cyclic is not None else 0,
        "rigid_body_directions": {"names": list(a.cyclic.names), "residual": a.cyclic.residual,
                                  "dropped": [list(x) for x in a.cyclic.dropped]}
        if a.cyclic is not None else None,
        "tolerances": {"safety": SAFETY, "invariant_tol": INVARIANT_TOL,
                       "formed_in": len(a.state.q),
                       "inf_tol": float(sol.details.get("inf_tol", 0.0)),
                       "rank_tol": float(lin.tolerances.get("rank_tol", 0.0))},
        "modes": [dict(r) for r in a.modes],
    }
