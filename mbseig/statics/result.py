"""The statics stage result (:class:`Equilibrium`) and how a solve is finished into one: the
multipliers, the residuals, the rank and redundancy of the constraints."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..numerics import dense
from ..records import Record, optional
from .linalg import (
    DENSE_LIMIT,
    multipliers,
)
from .position import constraint_residual


@dataclass(frozen=True, eq=False)
class Equilibrium:
    """q₀, λ₀ with their residuals, the rank of Φ_q(q₀) and the tolerances used.

    ``residual`` is the larger of ‖g − Φ_qᵀλ‖∞ / force_scale and max_k |Φ_k| / scale_k;
    ``correction`` the last Newton correction in the model's scales (the convergence test).
    ``static``: the static stability record (:func:`mbseig.statics.stiffness.static_stability`);
    ``self_stress``: self-stress states of redundant constraints that change the stiffness;
    ``stable_alternative``: a statically stable equilibrium offered when this one is unstable;
    ``path``: how it was reached (direct Newton or load continuation, iterations).
    """

    #: the reference motion this belongs to (mbseig.studies.reference): an equilibrium
    kind = "rest"

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
    correction: float = 0.0
    static: dict = field(default_factory=dict)
    self_stress: tuple = ()
    stable_alternative: object = None
    path: dict = field(default_factory=dict)
    notes: tuple = ()
    contacts: tuple = ()  # single-sided contacts: ({"name", "force", "active"}, ...) (DESIGN §8)


@dataclass(frozen=True, eq=False)
class StaticStability(Record):
    """The static stability of an equilibrium (:func:`mbseig.statics.stiffness.static_stability`):
    the verdict (stable, neutral, unstable, undetermined, not examined) from the reduced tangent
    stiffness K_r = Nᵀ(K + H(λ))N, its size ``dof``, whether it is symmetric (``asymmetry``
    relative to ‖K_r‖ against ``symmetry_tol``), the number of negative (``index``) and zero
    (``zero``) eigenvalues beyond ``stiffness_tol``·‖K_r‖, the smallest eigenvalue and its
    direction in full coordinates (both None when one Cholesky factorization showed K_r
    positive definite beyond the tolerance: no eigenvalue is computed then, and ``asymmetry``
    is the upper bound that decided); ``gyroscopic``: an unstable equilibrium whose velocity
    Jacobian has a skew part (gyroscopic forces may stabilize it); ``self_stress_tol`` and
    ``reason`` (why it was not examined) as recorded."""

    verdict: str  # stable, neutral, unstable, undetermined, not examined
    dof: int | None = optional()  # size of K_r
    stiffness_tol: float | None = optional()  # relative to ‖K_r‖: eigenvalues below are zero
    symmetry_tol: float | None = optional()  # relative asymmetry above which K_r is not symmetric
    symmetric: bool | None = optional()
    asymmetry: float | None = optional()  # ‖K_r − K_rᵀ‖/‖K_r‖ (or the bound that decided)
    min_eigenvalue: float | None = optional()  # None when Cholesky decided
    index: int | None = optional()  # negative eigenvalues beyond the tolerance
    zero: int | None = optional()  # eigenvalues within the tolerance
    direction: object = optional()  # of the smallest eigenvalue, in full coordinates
    gyroscopic: bool | None = optional()  # unstable, with a skew velocity Jacobian
    self_stress_tol: float | None = optional()
    reason: str | None = optional()  # why it was not examined


def solved(model, eq):
    """The model whose equilibrium ``eq`` is: ``eq.model`` when :func:`mbseig.equilibrium`
    resolved inverse-statics commands (actuator settings), else ``model`` itself.  Every stage
    after the equilibrium works on this model."""
    return eq.model if getattr(eq, "model", None) is not None else model


def reaction_records(model, lam) -> tuple:
    """(constraint name, its multipliers) per constraint element, in the model's order."""
    out, k = [], 0
    for c in model.constraints:
        out.append((c.name, lam[k:k + c.n_eq].copy()))
        k += c.n_eq
    return tuple(out)


def finish(model, q, s, *, iterations, correction, method, path, lam=None, memo=None):
    """The Equilibrium record at a converged q: least-squares λ, rank, residuals, reactions.
    memo: the :class:`Memo` of ``model`` the solve used (its evaluations at q, and its
    least-squares multipliers there, are reused)."""
    n, m = model.n, model.n_constraints
    ev = model if memo is None else memo
    Phi_q = ev.phi_q(q)
    g = ev.generalized_force(q)
    lam_ls, rank, rank_method = (multipliers(Phi_q, g, s.rank_tol, check=True) if memo is None
                                 else memo.least_squares(q, s.rank_tol, True))
    lam = lam_ls if lam is None else lam
    r1 = g - Phi_q.T @ lam
    fr = float(np.max(np.abs(r1), initial=0.0)) / s.force_scale
    cr = constraint_residual(ev, q, model.constraint_scales())[1]
    redundant = _redundant_rows(model, Phi_q, rank) if n + m <= DENSE_LIMIT else []
    return Equilibrium(
        q=q, lam=lam, residual=max(fr, cr), force_residual=fr, constraint_residual=cr,
        iterations=int(iterations), rank=rank, n_redundant=m - rank, redundant=tuple(redundant),
        reactions=reaction_records(model, lam),
        tolerances={**s.record(), "rank_method": rank_method},
        method=method, model=model, correction=float(correction), path=dict(path))


def _redundant_rows(model, Phi_q, rank):
    import scipy.linalg as sla

    m = Phi_q.shape[0]
    if rank >= m:
        return []
    _, _, piv = sla.qr(dense(Phi_q).T, pivoting=True, mode="economic")
    names = model.constraint_row_names()
    return sorted({names[i] for i in piv[rank:]})
