"""Error bounds of the reactions (:func:`mbseig.statics.reactions.reaction_forces`): a bound on
the multipliers' error from the least-squares solve's residual and σ_min(Φ_q), and values within
their bounds shown as 0."""

from __future__ import annotations

import math

import numpy as np
import scipy.sparse as sp

from .result import solved

__all__ = ["EPS", "ROUNDING_DEPTH", "DENSE_SVD_ENTRIES", "multiplier_error", "sigma_min",
           "bounded", "zeroed", "linear_map"]


EPS = float(np.finfo(float).eps)
#: floating-point operations between the multipliers and a reported value (a row's gradient,
#: a cross product and the transfer of a moment to the joint point), counted in the rounding
#: term γ = (n_λ + ROUNDING_DEPTH)·ε of :func:`multiplier_error`
ROUNDING_DEPTH = 8
#: entries of Φ_q up to which σ_min is found by a dense SVD (beyond: :func:`sigma_min`)
DENSE_SVD_ENTRIES = 250_000


def multiplier_error(model, eq) -> dict:
    """A bound on the error of the multipliers λ (least squares Φ_qᵀλ = g at q,
    :func:`mbseig.statics.linalg.multipliers`): ‖δλ‖₂ ≤ (‖g − Φ_qᵀλ‖₂ + γ_m (‖|Φ_q|ᵀ|λ|‖₂ +
    ‖g‖₂)) / σ⁺_min(Φ_q), the solve's residual at q (holding also the force the position solve
    left unbalanced) plus what rounding hides in it (γ_m = (k + 2)ε, k the longest column of
    Φ_q), over the smallest nonzero singular value of Φ_q (of the statics' rank; redundant
    constraints: λ the minimum-norm solution).  A value a·λ is then within ‖a‖₂ ‖δλ‖₂ +
    γ |a|·|λ|, γ = (n_λ + ROUNDING_DEPTH)ε (a spatial joint's force and moment count every term
    of their sums, :func:`_wrench`): the ``error`` beside every value."""
    model, lam = solved(model, eq), np.asarray(eq.lam, float)
    out = {"method": "(‖g − Φ_qᵀλ‖₂ + γ_m (‖|Φ_q|ᵀ|λ|‖₂ + ‖g‖₂)) / σ⁺_min(Φ_q)",
           "lambda_bound": 0.0, "residual": 0.0, "sigma_min": None, "rank": lam.size}
    if lam.size == 0:
        return out
    Phi = sp.csr_matrix(model.phi_q(eq.q))
    g = np.asarray(model.generalized_force(eq.q), float)
    res = float(np.linalg.norm(g - Phi.T @ lam))
    longest = int(np.diff(Phi.tocsc().indptr).max(initial=0))
    hidden = (longest + 2) * EPS * (float(np.linalg.norm(abs(Phi).T @ np.abs(lam)))
                                    + float(np.linalg.norm(g)))
    rank = int(getattr(eq, "rank", lam.size) or 0)
    sigma = sigma_min(Phi, rank)
    # σ not found (a large Φ_q with redundant rows) or zero: no bound, and no value is zeroed
    bound = (res + hidden) / sigma if sigma > 0 else math.nan
    out.update(lambda_bound=float(bound), residual=res,
               sigma_min=None if math.isnan(sigma) else float(sigma), rank=rank)
    return out


def sigma_min(Phi, rank):
    """σ⁺_min(Φ_q): the rank-th singular value (dense SVD), or for a large Φ_q of full row rank
    1/√‖(Φ_qΦ_qᵀ)⁻¹‖₁ ≤ σ_min (‖A⁻¹‖₂ ≤ ‖A⁻¹‖₁, A symmetric; ‖·‖₁ by Higham's estimate)."""
    m, n = Phi.shape
    if rank <= 0:
        return 0.0
    if m * n > DENSE_SVD_ENTRIES and rank < m:  # redundant and large: not estimated (no SVD)
        return math.nan
    if m * n <= DENSE_SVD_ENTRIES:
        import scipy.linalg as sla

        sv = sla.svdvals(Phi.toarray())
        return float(sv[min(rank, sv.size) - 1])
    import scipy.sparse.linalg as spla

    lu = spla.splu(sp.csc_matrix(Phi @ Phi.T))
    inv = spla.LinearOperator((m, m), matvec=lu.solve, rmatvec=lu.solve, dtype=float)
    return 1.0 / math.sqrt(float(spla.onenormest(inv)))


def bounded(A, lam, dlam, scale=None):
    """(values A λ with each one within its bound set to 0, the bounds): bound_i =
    ‖A_i‖₂ δλ + γ s_i, s_i = |A_i|·|λ| unless the caller gives the magnitudes ``scale``."""
    A = np.atleast_2d(np.asarray(A, float))
    lam = np.asarray(lam, float)
    gamma = (lam.size + ROUNDING_DEPTH) * EPS
    s = np.abs(A) @ np.abs(lam) if scale is None else np.asarray(scale, float)
    err = np.linalg.norm(A, axis=1) * dlam + gamma * s
    return zeroed(A @ lam, err), [float(e) for e in err]


def zeroed(values, err):  # + 0.0: no "-0" in reports
    return [0.0 if abs(v) <= e else float(v) + 0.0 for v, e in zip(values, err, strict=True)]


def linear_map(fn, n):
    """The matrix of a map linear in λ (n multipliers), column by column."""
    cols = [np.atleast_1d(np.asarray(fn(e), float)) for e in np.eye(n)]
    return np.column_stack(cols) if cols else np.zeros((0, 0))
