"""Static equilibrium of the constrained model (docs/design.md, "Equilibrium").

Solve, at q̇ = 0,

    g(q₀, 0) − Φ_q(q₀)ᵀ λ₀ = 0,        Φ(q₀) = 0

from the case's positions:

1. Position solve: q is moved onto Φ = 0 first (:mod:`~mbseig.statics.position`); a
   least-squares minimum with Φ ≠ 0 there is the only proof that the constraints cannot be
   satisfied.
2. Newton on the augmented system, kept on the constraint manifold:

       ┌ K + H(λ)   Φ_qᵀ ┐ ┌ Δq ┐   ┌ g − Φ_qᵀ λ ┐
       └   Φ_q       0   ┘ └ Δλ ┘ = └    −Φ      ┘        K = −∂g/∂q,  H(λ) = Σ λ_k ∇²Φ_k

   with λ always the least-squares multipliers of the current q (Φ_qᵀλ ≈ g), the step bounded
   by a trust radius in the model's length and angle scales
   (:class:`~mbseig.statics.linalg.StepScales`), each trial projected back onto Φ = 0 and
   accepted by Deuflhard's restricted monotonicity test on the *simplified Newton correction*
   (the correction the same matrix gives at the trial point): a test in displacements, not in
   forces, so that a stiff member strained by a linearized rotation does not reject a good step.
   Where the tangent stiffness has no restoring force along an unbalanced load (a pendulum
   started horizontal: λ = 0, K = 0), the step also moves along that force by the trust radius.
   A model above ``SMALL`` unknowns with frames (beams, spatial bodies) solves that augmented
   system on its local basis (:class:`LocalNewtonMatrix`: the node and body triads eliminated by
   their tangent space, the joints component by component), factorizing Nᵀ(K + H)N of the FE
   size and Φ_q Φ_qᵀ instead of the augmented matrix; the same correction, to rounding.  The
   corrector of a homotopy step (below) still solves the augmented matrix.
3. When that fails: continuation in the loads from the unloaded state
   (:mod:`~mbseig.statics.loads`); both are put together by
   :func:`mbseig.statics.solve.solve_statics`.

Convergence criterion (recorded in ``Equilibrium.tolerances["criterion"]``): every constraint
satisfied to ``tol`` of its own scale, the Newton correction of q below ``xtol`` in the model's
length and angle scales, and the generalized force that the tangent stiffness cannot balance
below ``tol`` × force_scale; when rounding stops the correction from decreasing, a correction
below ``floor_tol`` is accepted and recorded.  A correction is scale-aware where a force
residual is not: a stiff member's rounding noise, divided by its stiffness, is small.

λ₀ is finally the least-squares solution of Φ_qᵀλ = g (minimum norm), the redundancy is counted
and named, and the equilibrium's static stability, self-stress and a stable alternative are
examined (:mod:`~mbseig.statics.stiffness`, :func:`mbseig.statics.equilibrium`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from ..errors import EquilibriumError
from ..model.system import Model
from ..model.tangent import local_basis, triad_coordinates
from ..numerics import LazyModule
from .cache import Memo
from .linalg import (
    SMALL,
    NewtonMatrix,
    StepScales,
    augmented,
    multipliers,
    solve_bordered,
)
from .position import STATIONARY, constraint_residual, position_solve

spla = LazyModule("scipy.sparse.linalg")  # the particular solution's factor: at first use

__all__ = ["Settings", "Stall", "Solution", "newton", "static_multipliers", "force_scale",
           "settings_for", "CRITERION", "LocalNewtonMatrix", "local_newton"]

CRITERION = ("max_k |Φ_k|/scale_k ≤ tol; Newton correction max(|Δq_i|/ℓ_i, |Δd_b|/L_b) ≤ xtol "
             "(ℓ: length scale for point coordinates, 1 rad for angles; d_b: rigid lengths); "
             "force outside the range of the tangent stiffness ≤ tol·force_scale; λ the "
             "least-squares multipliers of q (a correction ≤ floor_tol is accepted where rounding "
             "stops it from decreasing)")


# ---------------------------------------------------------------------------------------------
@dataclass
class Settings:
    """Tolerances and limits of one static solve (all recorded in the result)."""

    tol: float = 1e-12
    xtol: float = 1e-12
    floor_tol: float = 1e-8
    max_iter: int = 50
    rank_tol: float = 1e-10
    radius: float = 0.25  # initial trust radius (model lengths / radians)
    radius_max: float = 1.0
    force_scale: float = 1.0
    scales: StepScales = None

    def record(self) -> dict:
        return {"tol": self.tol, "xtol": self.xtol, "floor_tol": self.floor_tol,
                "max_iter": self.max_iter, "rank_tol": self.rank_tol,
                "trust_radius": self.radius, "trust_radius_max": self.radius_max,
                "force_scale": self.force_scale, "length_scale": self.scales.length,
                "criterion": CRITERION, "monotonicity": MONOTONICITY,
                "full_step_max": FULL_STEP_MAX, "free_steps": FREE_STEPS,
                "corrector_iter": CORRECTOR_ITER, "corrector_tol": CORRECTOR_TOL,
                "stationary": STATIONARY}


class Stall(Exception):
    """Newton stopped without convergence; carries the last iterate for the diagnosis."""

    def __init__(self, reason, *, q=None, lam=None, free_dir=None, free=0.0, correction=np.inf,
                 iterations=0, cond=np.nan):
        super().__init__(reason)
        self.reason, self.q, self.lam = reason, q, lam
        self.free_dir, self.free, self.correction = free_dir, free, correction
        self.iterations, self.cond = iterations, cond


@dataclass
class Solution:
    q: np.ndarray
    lam: np.ndarray
    iterations: int
    correction: float
    free: float
    position_iterations: int
    rounding: bool = False
    cond: float = np.nan


def static_multipliers(model, q, s):
    """λ of the statics at q: the minimum-norm solution of Φ_qᵀλ = g (rank by ``s.rank_tol``)."""
    kept = getattr(model, "least_squares", None)  # a Memo: once per q
    if kept is not None:
        return kept(q, s.rank_tol, False)[0]
    return multipliers(model.phi_q(q), model.generalized_force(q), s.rank_tol, check=False)[0]


def _rhs(model, q, lam, s):
    with np.errstate(all="ignore"):
        r1 = model.generalized_force(q) - model.phi_q(q).T @ lam
        phi = model.phi(q)
    return np.concatenate([r1, -phi])


def _measure(NM, rhs, n, s):
    """(Newton correction x, its size in the model's scales, unbalanced free force / F, e_q)."""
    x, e = NM.solve(rhs)
    eq_ = e[:n]
    return x, s.scales.size(x[:n]), float(np.max(np.abs(eq_), initial=0.0)) / s.force_scale, eq_


def _second_order(model, q, lam, step, NM, rhs0, n, s):
    """The curvature correction of a step (module docstring): σ = J⁺ ½ (R(q+s) + R(q−s) − 2R(q))
    with λ held, so that a rotation does not strain stiff members or leave the constraints.
    Dropped (zero) when it is not finite or larger than half the step."""
    with np.errstate(all="ignore"):
        try:
            c = 0.5 * (_rhs(model, q + step, lam, s) + _rhs(model, q - step, lam, s) - 2.0 * rhs0)
            sigma = NM.solve(c)[0][:n]
        except (EquilibriumError, ArithmeticError, ValueError):
            return np.zeros(n)
    if not np.all(np.isfinite(sigma)) or s.scales.size(sigma) > 0.5 * s.scales.size(step):
        return np.zeros(n)
    return sigma


def _trial(model, q, lam, step, NM, rhs0, n, s):
    """q + step + curvature correction, projected onto Φ = 0; (q_t, λ_t, x_t, e_t) or None."""
    qt, _ = position_solve(model, q + step + _second_order(model, q, lam, step, NM, rhs0, n, s),
                           s.scales, tol=s.tol, max_iter=12, radius=max(s.radius, 0.5), prove=False)
    if qt is None:
        return None
    try:
        with np.errstate(all="ignore"):
            lt = static_multipliers(model, qt, s)
            xt, et = NM.solve(_rhs(model, qt, lt, s))
    except (EquilibriumError, ArithmeticError, ValueError):
        return None
    if not (np.all(np.isfinite(xt)) and np.all(np.isfinite(et))):
        return None
    return qt, lt, xt, et


MONOTONICITY = 0.75  # a full Newton step is taken when θ = ‖Δx̄‖/‖Δx‖ is below it
FULL_STEP_MAX = 10.0  # a full Newton step longer than this (model sizes) is not even tried
FREE_STEPS = 5  # free steps without the unbalanced force dropping by 1 % show a free motion
CORRECTOR_ITER = 8  # Newton iterations of the corrector of a homotopy step
CORRECTOR_TOL = 1e-3  # the corrector has converged when its correction is below this × the step


def _homotopy_step(model, q, lam, NM, R, x, motion, h, s):
    """One predictor–corrector step of length h (model's scales) on the Newton homotopy
    F(y, τ) = R(y) − (1 − τ) R_k = 0 from y_k = (q, λ) at τ = 0, pseudo-arclength in q
    (module docstring).  Returns (q, λ) on Φ = 0 with λ least-squares, or None."""
    n, N = model.n, R.size
    if motion is not None:  # J singular, R_k outside its range: leave along the free motion
        yd, td = motion.copy(), 0.0
    else:  # the tangent (J⁻¹R_k, 1): the Newton direction
        yd, td = x.copy(), 1.0
    nq = s.scales.size(yd[:n])
    if not nq or not np.isfinite(nq):
        return None
    yd, td = yd / nq, td / nq
    y = np.concatenate([q, lam]) + h * yd
    y[:n] += _second_order(model, q, lam, h * yd[:n], NM, R, n, s)
    tau = h * td
    qp = y[:n].copy()
    c = np.concatenate([yd[:n] / s.scales.ell**2, np.zeros(N - n)])
    for _ in range(CORRECTOR_ITER):
        qy, ly = y[:n], y[n:]
        try:
            with np.errstate(all="ignore"):
                F = _rhs(model, qy, ly, s) - (1.0 - tau) * R
                A, _ = augmented(model, qy, ly)
                dy, dtau = solve_bordered(A, -R, c, 0.0, F, -(c[:n] @ (qy - qp)),
                                          weights=s.scales.weights(N + 1))
                dz = np.concatenate([dy, [dtau]])
        except (EquilibriumError, ArithmeticError, ValueError):
            return None
        if not np.all(np.isfinite(dz)):
            return None
        y = y + dz[:N]
        tau += dz[N]
        step = s.scales.size(dz[:n])
        if step > h:
            return None
        if step <= max(CORRECTOR_TOL * h, s.xtol):
            break
    else:
        return None
    qn, _ = position_solve(model, y[:n], s.scales, tol=s.tol, max_iter=8, prove=False)
    if qn is None:
        return None
    try:
        with np.errstate(all="ignore"):
            ln = static_multipliers(model, qn, s)
    except (EquilibriumError, ArithmeticError, ValueError):
        return None
    return (qn, ln) if np.all(np.isfinite(ln)) else None


LU_MARGIN = 0.5  # the LU's test of convergence at the start: within half the tolerances


def _converged_by_lu(A, rhs, q, lam, n, s, cscale_model, pit):
    """The Solution at the start q when it has converged already, judged on a dense LU of a
    small (up to ``SMALL`` unknowns) well-conditioned Newton matrix (:class:`NewtonMatrix`
    ``lu_first``, several times cheaper than its SVD), else None.  Its correction differs from
    the SVD's by cond·ε of itself, so within ``LU_MARGIN`` of the tolerances the SVD's test
    passes too: q is returned as the SVD would return it (only the recorded correction differs,
    by rounding); everywhere else the iteration goes on as before, on the SVD.
    A right-hand side of exact zeros needs no factorization (x = 0, e = 0 from any); the
    condition number is then not computed (NaN, as for an LU).  (cscale_model: (model,
    constraint scales) for the constraint residual.)"""
    model, cscale = cscale_model
    if A.shape[0] > SMALL:  # (a large matrix: the sparse LU as before)
        return None
    finite = bool(np.all(np.isfinite(A.data if sp.issparse(A) else A)))
    if not finite:  # (left to the SVD, whose error the caller reports)
        return None
    if not np.any(rhs):  # balanced exactly: every factorization gives x = 0, e = 0
        if constraint_residual(model, q, cscale)[1] <= s.tol:
            return Solution(q, lam, 0, 0.0, 0.0, pit, cond=float("nan"))
        return None
    try:
        NM = NewtonMatrix(A, weights=s.scales.weights(A.shape[0]), lu_first=True)
    except EquilibriumError:
        return None
    if NM.kind != "lu" or NM.dense_lu is None:
        return None
    _, corr, free, _ = _measure(NM, rhs, n, s)
    cr = constraint_residual(model, q, cscale)[1]
    if (np.isfinite(corr) and cr <= s.tol and corr <= LU_MARGIN * s.xtol
            and free <= LU_MARGIN * s.tol):
        return Solution(q, lam, 0, corr, free, pit, cond=NM.cond)
    return None


class LocalNewtonMatrix:
    """The augmented Newton matrix [[A, Φ_qᵀ], [Φ_q, 0]] at q (A = K + H(λ)) of a large model
    with frames, solved on its local basis N (:mod:`mbseig.model.tangent`) instead of factorized
    whole: the interface of :class:`~mbseig.statics.linalg.NewtonMatrix` (``solve``, ``motion``,
    ``cond``), made by :func:`local_newton`.

    Where Φ_q has full row rank and N spans its null space, the solution of
    [[A, Φ_qᵀ], [Φ_q, 0]] [Δq; Δλ] = [r₁; r₂] is Δq = Δq_p + N y with Φ_q Δq_p = r₂ (any
    particular solution: another one differs by a motion in span N, which y takes back) and
    Nᵀ A N y = Nᵀ (r₁ − A Δq_p), since Nᵀ Φ_qᵀ = 0; then Φ_qᵀ Δλ = r₁ − A Δq, whose right-hand
    side lies in the range of Φ_qᵀ (Nᵀ of it is zero), so Δλ = (Φ_q Φ_qᵀ)⁻¹ Φ_q (r₁ − A Δq).
    Δq_p = Φ_qᵀ (Φ_q Φ_qᵀ)⁻¹ r₂.  The matrices factorized are Nᵀ A N (the FE size) and Φ_q Φ_qᵀ
    (Φ_q's rows), not the augmented matrix: a beam model of 10⁵ DOF factorizes 100,012 and
    105,500 unknowns instead of 305,524 (the augmented SuperLU: 120 MB)."""

    kind = "local"

    def __init__(self, N, A, Phi_q, reduced, rows):
        self.N, self.A, self.Phi_q = N, A, Phi_q
        self.reduced, self.rows = reduced, rows  # NewtonMatrix of NᵀAN; SuperLU of Φ_qΦ_qᵀ
        self.n = A.shape[0]
        self.cond = reduced.cond
        self.rank = self.n + Phi_q.shape[0]

    def solve(self, b):
        n = self.n
        r1, r2 = b[:n], b[n:]
        with np.errstate(all="ignore"):
            dq_p = self.Phi_q.T @ self.rows.solve(r2) if np.any(r2) else np.zeros(n)
            y, e = self.reduced.solve(self.N.T @ (r1 - self.A @ dq_p))
            dq = dq_p + self.N @ y
            dlam = self.rows.solve(self.Phi_q @ (r1 - self.A @ dq))
        return np.concatenate([dq, dlam]), np.concatenate([self.N @ e, np.zeros(r2.size)])

    def motion(self, b):
        """No motion without restoring force: the reduced matrix is nonsingular."""
        return np.zeros_like(b)


def local_newton(model, q, lam, s):
    """The :class:`LocalNewtonMatrix` at (q, λ) of a model above ``SMALL`` unknowns with frames,
    or None where the local basis does not give the augmented solve (no frames, dependent
    constraints, rows left to a bordered pencil, dense evaluations, a value that is not finite,
    a singular Φ_q Φ_qᵀ or reduced matrix: a free motion, whose least step in the model's
    metric is the augmented matrix's to give)."""
    m, n = model.n_constraints, model.n
    if n + m <= SMALL:
        return None
    base = model.model if isinstance(model, Memo) else model
    if not isinstance(base, Model) or triad_coordinates(base)[0].shape[0] == 0:
        return None
    local = local_basis(base, q, s.rank_tol)
    if local.kept is not None or local.rank != m:
        return None
    K, _ = model.force_jacobians(q)
    A = K + model.constraint_hessian(q, lam) if m else K
    if not sp.issparse(A) or not np.all(np.isfinite(A.data)):
        return None
    A = A.tocsr()
    Phi_q = model.phi_q(q)
    with np.errstate(all="ignore"):
        try:
            rows = spla.splu(sp.csc_matrix(Phi_q @ Phi_q.T))
        except RuntimeError:  # (Φ_q Φ_qᵀ singular: left to the augmented matrix)
            return None
    N = local.N
    try:
        reduced = NewtonMatrix((N.T @ (A @ N)).tocsr(), what="reduced Newton matrix",
                               lu_first=True)
    except EquilibriumError:
        return None
    if reduced.rank < N.shape[1]:
        return None
    return LocalNewtonMatrix(N, A, Phi_q, reduced, rows)


def newton(model, q, s: Settings, *, max_iter=None, prove=True) -> Solution:
    """Newton from q (module docstring, step 2).  Raises :class:`Stall` or, from the position
    solve, :class:`~mbseig.statics.failures.ConstraintsUnsatisfiable` (when ``prove``).

    A full Newton step inside the trust radius is taken when it passes the restricted
    monotonicity test θ = ‖Δx̄‖/‖Δx‖ < 3/4 on the simplified correction.  Otherwise (a step
    longer than the trust radius, a rejected full step, or a force the Newton matrix cannot
    balance) a *homotopy step* of the trust radius: predictor along the Newton direction, or
    along the free motion the unbalanced force pushes, corrected by Newton on the Newton
    homotopy R(y) = (1 − τ) R_k with a pseudo-arclength condition (:func:`_homotopy_step`).
    The corrector lets stiff members relax while the soft motion advances, so a rotation does
    not strain them.  A step whose corrector fails is halved."""
    max_iter = s.max_iter if max_iter is None else max_iter
    n = model.n
    q0 = np.array(q, dtype=float)
    q, pit = position_solve(model, q0, s.scales, tol=s.tol, radius=max(s.radius, 0.5), prove=prove)
    if q is None:
        raise Stall("the position solve did not reach Φ = 0", q=q0, iterations=0)
    cscale = model.constraint_scales()
    lam = static_multipliers(model, q, s)
    radius = s.radius
    it = 0
    free_streak, free_last = 0, np.inf
    while True:
        rhs = _rhs(model, q, lam, s)
        NM = local_newton(model, q, lam, s)  # (a large model with frames: no augmented matrix)
        if NM is None:
            A, _ = augmented(model, q, lam)
            if it == 0:  # converged already? (the usual start: the case's positions)
                done = _converged_by_lu(A, rhs, q, lam, n, s, (model, cscale), pit)
                if done is not None:
                    return done
            try:
                NM = NewtonMatrix(A, weights=s.scales.weights(A.shape[0]))
            except EquilibriumError as exc:
                raise Stall(exc.message, q=q, lam=lam, iterations=it) from None
        x, corr, free, e_q = _measure(NM, rhs, n, s)
        cr = constraint_residual(model, q, cscale)[1]
        if not np.isfinite(corr):
            raise Stall("the Newton correction is not finite", q=q, lam=lam, iterations=it)
        if cr <= s.tol and corr <= s.xtol and free <= s.tol:
            return Solution(q, lam, it, corr, free, pit, cond=NM.cond)
        stall = dict(q=q, lam=lam, free_dir=e_q if free > s.tol else None, free=free,
                     correction=corr, iterations=it, cond=NM.cond)
        if it >= max_iter:
            raise Stall(f"no convergence in {max_iter} Newton iterations", **stall)
        it += 1
        motion = None
        if free > s.tol:  # a force outside the range: the free motion it pushes along, if any
            motion = NM.motion(np.concatenate([e_q, np.zeros(rhs.size - n)]))
            if not s.scales.size(motion[:n]):
                motion = None
        free_step = motion is not None
        if free_step:  # moving freely without the unbalanced force dropping: a free motion
            free_streak = free_streak + 1 if free > 0.99 * free_last else 0
            free_last = free
            if free_streak >= FREE_STEPS:
                raise Stall(f"free motion: {FREE_STEPS} steps along the unbalanced force did "
                            f"not reduce it", **stall)
        if not free_step and corr <= FULL_STEP_MAX:  # the full step, when it passes the test
            tr = _trial(model, q, lam, x[:n], NM, rhs, n, s)
            if tr is not None and s.scales.size(tr[2][:n]) < MONOTONICITY * corr:
                if s.scales.size(tr[2][:n]) < 0.25 * corr:
                    radius = min(2.0 * radius, s.radius_max)
                q, lam = tr[0], tr[1]
                continue
            if corr <= s.floor_tol and cr <= s.tol:
                # rounding: the correction no longer decreases; accepted below floor_tol
                return Solution(q, lam, it - 1, corr, free, pit, rounding=True, cond=NM.cond)
        h = radius if free_step else min(radius, corr)
        h0 = h
        while True:
            res = _homotopy_step(model, q, lam, NM, rhs, x, motion, h, s)
            if res is not None:
                break
            h *= 0.5
            if h < 1e-13:
                raise Stall("the trust region shrank to nothing (no homotopy step converges)",
                            **stall)
        radius = min(2.0 * radius, s.radius_max) if h == h0 else max(h, 1e-6)
        q, lam = res


# ---------------------------------------------------------------------------------------------
def force_scale(model, q, rank_tol):
    """Typical generalized force at q: loads, or stiffness times the model's size."""
    with np.errstate(all="ignore"):
        g = model.generalized_force(q)
        K, _ = model.force_jacobians(q)
        Phi_q = model.phi_q(q)
        kept = getattr(model, "least_squares", None)  # a Memo: once per q
        lam = (kept(q, rank_tol, False)[0] if kept is not None else
               multipliers(Phi_q, g, rank_tol, check=False)[0])
        if sp.issparse(K):
            K = K.tocsr()
            knorm = (float(np.max(np.add.reduceat(np.abs(K.data),
                                                  K.indptr[:-1][np.diff(K.indptr) > 0])))
                     if K.nnz else 0.0)  # ‖K‖_∞ (row sums of the nonempty rows)
        else:
            knorm = float(np.max(np.abs(K).sum(axis=1), initial=0.0))
        f = max(float(np.max(np.abs(g), initial=0.0)), knorm * model.length_scale,
                float(np.max(np.abs(Phi_q.T @ lam), initial=0.0)))
    return f if np.isfinite(f) and f > 0 else 1.0


def settings_for(model, q, *, tol, xtol, floor_tol, max_iter, rank_tol):
    s = Settings(tol=tol, xtol=tol if xtol is None else xtol, floor_tol=floor_tol,
                 max_iter=max_iter, rank_tol=rank_tol)
    s.scales = StepScales.of(model)  # (the same scales for the models of one device)
    s.force_scale = force_scale(model, q, rank_tol)
    return s
