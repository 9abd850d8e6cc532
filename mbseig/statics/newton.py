"""Static equilibrium of the constrained model (docs/design.md, "Equilibrium").

Solve, at q̇ = 0,

    g(q₀, 0) − Φ_q(q₀)ᵀ λ₀ = 0,        Φ(q₀) = 0

by Newton's method on the augmented system from the case's initial positions:

    ┌ K + H(λ)   Φ_qᵀ ┐ ┌ Δq ┐   ┌ g − Φ_qᵀ λ ┐
    └   Φ_q       0   ┘ └ Δλ ┘ = └    −Φ      ┘        K = −∂g/∂q,  H(λ) = Σ λ_k ∇²Φ_k

with a backtracking line search on the scaled residual.  The step is the minimum-norm
least-squares solution (SVD), so redundant constraints and rigid-body freedoms do not stop it;
λ₀ is finally recomputed as the minimum-norm solution of Φ_qᵀ λ = g and the redundancy reported.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ..errors import EquilibriumError, MbseigError
from ..model.linear_case import LinearCase
from ..numerics import constraint_rank

__all__ = ["Equilibrium", "solve_statics", "solved"]

NONMONOTONE_MEMORY = 5  # merits the line search compares against (1: monotone)
DENSE_LIMIT = 4000  # augmented size up to which the Newton step is a dense SVD least-squares solve


@dataclass(frozen=True, eq=False)
class Equilibrium:
    """q₀, λ₀ with their residuals, the rank of Φ_q(q₀) and the tolerances used.

    ``residual`` is the larger of ‖g − Φ_qᵀλ‖∞ / force_scale and max_k |Φ_k| / scale_k.
    """

    q: np.ndarray
    lam: np.ndarray
    residual: float
    force_residual: float
    constraint_residual: float
    iterations: int
    rank: int
    n_redundant: int
    redundant: tuple = ()
    reactions: tuple = ()  # (constraint name, λ values) per constraint element
    tolerances: dict = field(default_factory=dict)
    method: str = "newton"
    model: object = None  # the model this is the equilibrium of (commands resolved), see solved()


def solved(model, eq):
    """The model whose equilibrium ``eq`` is: ``eq.model`` when :func:`mbseig.equilibrium`
    resolved inverse-statics commands (actuator settings), else ``model`` itself.  Every stage
    after the equilibrium works on this model."""
    return eq.model if getattr(eq, "model", None) is not None else model


def solve_statics(model, *, tol: float = 1e-12, max_iter: int = 50, rank_tol: float = 1e-10,
                  q_init=None) -> Equilibrium:
    """Find the static equilibrium of ``model`` as it is (see the module docstring).

    tol : relative residual at which Newton stops (forces scaled by ``force_scale``, each
        constraint by its own scale, e.g. L² for a rigid length).
    rank_tol : relative singular-value threshold for the rank of Φ_q (redundancy count).
    Errors name the case file and the constraint or coordinate that could not be balanced.
    """
    try:
        return _equilibrium(model, tol=tol, max_iter=max_iter, rank_tol=rank_tol, q_init=q_init)
    except MbseigError as exc:
        raise exc.located(file=getattr(model, "source", None)) from None


def _equilibrium(model, *, tol, max_iter, rank_tol, q_init):
    if isinstance(model, LinearCase):
        return Equilibrium(q=np.zeros(model.n), lam=np.zeros(0), residual=0.0, force_residual=0.0,
                           constraint_residual=0.0, iterations=0, rank=0, n_redundant=0,
                           tolerances={"tol": tol, "rank_tol": rank_tol}, method="linear case",
                           model=model)
    n, m = model.n, model.n_constraints
    q = np.array(model.q_init if q_init is None else q_init, dtype=float)
    cscale = model.constraint_scales()
    Phi_q = model.phi_q(q)
    g = model.generalized_force(q)
    large = n + m > DENSE_LIMIT
    lam = _multipliers(Phi_q, g, rank_tol, large, check=False)[0]
    K, _ = model.force_jacobians(q)
    force_scale = _force_scale(model, g, K, Phi_q, lam)

    def residuals(q, lam):
        Phi_q = model.phi_q(q)
        r1 = model.generalized_force(q) - Phi_q.T @ lam
        r2 = model.phi(q)
        fr = float(np.max(np.abs(r1), initial=0.0)) / force_scale
        cr = float(np.max(np.abs(r2) / cscale, initial=0.0))
        return r1, r2, fr, cr, Phi_q

    r1, r2, fr, cr, Phi_q = residuals(q, lam)
    it = 0
    recent = []  # merits of the last NONMONOTONE_MEMORY iterates
    while max(fr, cr) > tol:
        if it >= max_iter:
            raise _failure(model, q, r1, r2, fr, cr, max_iter)
        it += 1
        K, _ = model.force_jacobians(q)
        H = model.constraint_hessian(q, lam)
        A = sp.bmat([[K + H, Phi_q.T], [Phi_q, None]], format="csr") if m else (K + H).tocsr()
        rhs = np.concatenate([r1, -r2])
        step = _solve(A, rhs)
        dq, dl = step[:n], step[n:]
        # non-monotone line search (Grippo, Lampariello & Lucidi 1986): a step is accepted when
        # it improves on the worst of the last few merits, so that a stiff elastic member
        # (a beam's EA stretched by a step's linearized rotation) does not stall Newton
        recent = (recent + [max(fr, cr)])[-NONMONOTONE_MEMORY:]
        merit = max(recent)
        alpha = 1.0
        for _ in range(40):
            qt, lt = q + alpha * dq, lam + alpha * dl
            try:
                r1t, r2t, frt, crt, Phi_qt = residuals(qt, lt)
            except EquilibriumError:
                frt = crt = np.inf
            if max(frt, crt) < merit or alpha < 1e-9:
                break
            alpha *= 0.5
        if not np.isfinite(max(frt, crt)):
            raise _failure(model, q, r1, r2, fr, cr, it)
        if max(frt, crt) >= merit and alpha < 1e-9:
            raise _failure(model, q, r1, r2, fr, cr, it)
        q, lam, r1, r2, fr, cr, Phi_q = qt, lt, r1t, r2t, frt, crt, Phi_qt

    g = model.generalized_force(q)
    lam, rank, rank_method = _multipliers(Phi_q, g, rank_tol, large, check=True)
    r1, r2, fr, cr, Phi_q = residuals(q, lam)
    redundant = _redundant_rows(model, Phi_q, rank) if not large else []
    reactions, k = [], 0
    for c in model.constraints:
        reactions.append((c.name, lam[k:k + c.n_eq].copy()))
        k += c.n_eq
    return Equilibrium(
        q=q, lam=lam, residual=max(fr, cr), force_residual=fr, constraint_residual=cr,
        iterations=it, rank=rank, n_redundant=m - rank, redundant=tuple(redundant),
        reactions=tuple(reactions),
        tolerances={"tol": tol, "max_iter": max_iter, "rank_tol": rank_tol,
                    "force_scale": force_scale, "rank_method": rank_method},
        model=model,
    )


def _force_scale(model, g, K, Phi_q, lam):
    """Typical generalized force: loads, or stiffness times the model's size."""
    knorm = sp.linalg.norm(K, np.inf) if K.nnz else 0.0
    s = max(float(np.max(np.abs(g), initial=0.0)), knorm * model.length_scale,
            float(np.max(np.abs(Phi_q.T @ lam), initial=0.0)))
    return s if s > 0 else 1.0


def _multipliers(Phi_q, g, rank_tol, large, *, check):
    """(λ, rank of Φ_q, how the rank was found) with λ the least-squares solution of Φ_qᵀλ = g.

    Dense (size up to DENSE_LIMIT): SVD, so λ is the minimum-norm solution and the rank is
    revealed by the singular values.  Large models: the normal equations Φ_q Φ_qᵀ λ = Φ_q g by
    sparse LU; that needs independent constraints, so a pivot below rank_tol² of the largest
    (the square, since Φ_qΦ_qᵀ squares the singular values) raises instead of guessing.
    """
    m = Phi_q.shape[0]
    if m == 0:
        return np.zeros(0), 0, "none"
    if not large:
        lam = sla.lstsq(Phi_q.toarray().T, g, lapack_driver="gelsd")[0]
        rank = constraint_rank(Phi_q, rank_tol)[0] if check else m
        return lam, rank, "SVD of Φ_q"
    A = (Phi_q @ Phi_q.T).tocsc()
    try:
        lu = spla.splu(A)
    except RuntimeError:
        lu = None
    pivots = np.abs(lu.U.diagonal()) if lu is not None else np.zeros(1)
    if lu is None or pivots.min() <= rank_tol**2 * pivots.max():
        raise EquilibriumError(
            f"redundant constraints in a model of {Phi_q.shape[1]} coordinates and {m} constraints: "
            f"above the dense limit of {DENSE_LIMIT} the constraints must be independent",
            element="equilibrium")
    return lu.solve(Phi_q @ g), m, "sparse LU of Φ_q Φ_qᵀ (independent constraints verified by its pivots)"


def _solve(A, rhs):
    if A.shape[0] <= DENSE_LIMIT:
        return sla.lstsq(A.toarray(), rhs, lapack_driver="gelsd")[0]
    try:
        return spla.splu(A.tocsc()).solve(rhs)
    except RuntimeError:
        raise EquilibriumError(
            f"singular Newton matrix of size {A.shape[0]} (redundant constraints or free motion in "
            f"a model above the dense limit of {DENSE_LIMIT})", element="equilibrium") from None


def _redundant_rows(model, Phi_q, rank):
    m = Phi_q.shape[0]
    if rank >= m:
        return []
    _, _, piv = sla.qr(Phi_q.toarray().T, pivoting=True, mode="economic")
    names = model.constraint_row_names()
    return sorted({names[i] for i in piv[rank:]})


def _failure(model, q, r1, r2, fr, cr, iterations):
    if cr >= fr and r2.size:
        k = int(np.argmax(np.abs(r2) / model.constraint_scales()))
        name = model.constraint_row_names()[k]
        return EquilibriumError(
            f"no equilibrium after {iterations} Newton iterations: constraint cannot be satisfied "
            f"(relative residual {cr:.3g}); constraints are inconsistent", element=name)
    k = int(np.argmax(np.abs(r1)))
    coord = model.coordinate_names[k]
    return EquilibriumError(
        f"no equilibrium after {iterations} Newton iterations: unbalanced generalized force "
        f"{r1[k]:.4g} on coordinate {coord} (relative residual {fr:.3g}); is the model free to "
        f"move under its loads?", element="equilibrium")
