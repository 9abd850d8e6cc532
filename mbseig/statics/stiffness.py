"""The reduced tangent stiffness at an equilibrium: static stability and self-stress
(docs/design.md, "Equilibrium").

With N an orthonormal basis of null Φ_q(q₀) (the rank rule of :mod:`mbseig.numerics`),

    K_r = Nᵀ (K + Σ λ₀,k ∇²Φ_k) N.

Static stability.  The equilibrium is statically unstable (a divergence) when K_r is symmetric
(within ``SYMMETRY_TOL``) and has an eigenvalue below −``stiffness_tol``·‖K_r‖ (the potential is
not a minimum: unstable with any dissipation), or when K_r is not symmetric and det K_r < 0 (an
odd number of negative real eigenvalues: a real positive root s of det(M s² + P s + K_r) for any
M > 0, P).  ``index`` counts the negative eigenvalues.  A non-symmetric K_r with det K_r > 0 is
left to the modes ("undetermined" here).

Self-stress.  Redundant constraints leave Φ_qᵀ μ = 0 for μ ≠ 0 (the left null space of Φ_q):
every λ₀ + t μ balances the loads, statics cannot choose t, and the stiffness changes with it by
t Nᵀ H(μ) N.  A state μ (unit norm) whose ‖Nᵀ H(μ) N‖ exceeds ``self_stress_tol``·‖H(μ)‖ changes
the stiffness: reported with the constraints it loads.  A compliance c_k per constraint (the
extension of the element per unit of the force it carries, as the element reports it) makes the
multipliers those of least complementary energy, Σ c_k N_k(λ)² minimal among the λ that balance
the loads (Menabrea): :func:`compliant_multipliers`.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as sla

from ..numerics import dense
from .result import StaticStability

__all__ = ["reduced_stiffness", "static_stability", "self_stress_states", "compliant_multipliers",
           "STIFFNESS_TOL", "SYMMETRY_TOL", "SELF_STRESS_TOL"]

STIFFNESS_TOL = 1e-9  # relative: an eigenvalue of K_r below −tol·‖K_r‖ is a negative stiffness
SYMMETRY_TOL = 1e-10  # relative asymmetry below which K_r is treated as symmetric
SELF_STRESS_TOL = 1e-8  # relative stiffness change of a unit self-stress that counts


def _basis(model, q, rank_tol):
    Phi_q = dense(model.phi_q(q, dense=True))
    if Phi_q.shape[0] == 0:
        return np.eye(model.n), np.zeros((0, 0)), Phi_q, 0
    U, s, Vt = sla.svd(Phi_q, full_matrices=True)
    rank = int(np.sum(s > rank_tol * s[0])) if s.size and s[0] > 0 else 0
    return Vt[rank:].T, U[:, rank:], Phi_q, rank


def reduced_stiffness(model, q, lam, rank_tol=1e-10):
    """(K_r, N) at q with multipliers λ."""
    N, _, _, _ = _basis(model, q, rank_tol)
    K, _ = model.force_jacobians(q, dense=True)
    Kt = dense(K)
    if model.n_constraints:
        Kt = Kt + dense(model.constraint_hessian(q, lam, dense=True))
    return N.T @ Kt @ N, N


def static_stability(model, q, lam, *, rank_tol=1e-10, stiffness_tol=STIFFNESS_TOL,
                     symmetry_tol=SYMMETRY_TOL) -> StaticStability:
    """The static-stability record (module docstring)."""
    return StaticStability(**_stability(model, q, lam, rank_tol, stiffness_tol, symmetry_tol))


def _stability(model, q, lam, rank_tol, stiffness_tol, symmetry_tol) -> dict:
    Kr, N = reduced_stiffness(model, q, lam, rank_tol)
    rec = {"dof": int(Kr.shape[0]), "stiffness_tol": stiffness_tol, "symmetry_tol": symmetry_tol}
    if Kr.shape[0] == 0:
        return {**rec, "verdict": "stable", "index": 0, "symmetric": True, "min_eigenvalue": None,
                "direction": None}
    norm = float(np.linalg.norm(Kr, 2)) or 1.0
    asym = float(np.linalg.norm(Kr - Kr.T, 2)) / norm
    symmetric = asym <= symmetry_tol
    rec["symmetric"] = bool(symmetric)
    rec["asymmetry"] = asym
    if symmetric:
        mu, V = np.linalg.eigh(0.5 * (Kr + Kr.T))
        index = int(np.sum(mu < -stiffness_tol * norm))
        zero = int(np.sum(np.abs(mu) <= stiffness_tol * norm))
        rec.update(min_eigenvalue=float(mu[0]), index=index, zero=zero,
                   direction=N @ V[:, 0],
                   verdict="unstable" if index else ("neutral" if zero else "stable"))
        return rec
    mu, V = np.linalg.eig(Kr)
    real = np.abs(mu.imag) <= stiffness_tol * norm
    neg = real & (mu.real < -stiffness_tol * norm)
    index = int(np.sum(neg))
    k = int(np.argmin(np.where(real, mu.real, np.inf))) if real.any() else None
    rec.update(min_eigenvalue=None if k is None else float(mu[k].real), index=index,
               direction=None if k is None else N @ V[:, k].real,
               verdict="unstable" if index % 2 == 1 else ("undetermined" if index else "stable?"))
    if rec["verdict"] == "stable?":  # no negative real eigenvalue: statics sees no divergence
        rec["verdict"] = "stable" if np.all(mu.real > stiffness_tol * norm) else "undetermined"
    return rec


def self_stress_states(model, q, *, rank_tol=1e-10, tol=SELF_STRESS_TOL, states=None) -> list:
    """Self-stress states that change the stiffness: [{"constraints", "mu", "stiffness_change"}].

    states : columns spanning the self-stress states to examine (default: the whole left null
        space of Φ_q).
    """
    N, Uo, Phi_q, rank = _basis(model, q, rank_tol)
    Uo = Uo if states is None else states
    out = []
    if Uo.shape[1] == 0:
        return out
    names = model.constraint_row_names()
    # an orthonormal basis of the stiffness changes Nᵀ H(μ) N over the states: one record per
    # independent change (the states that change nothing are dropped)
    changes = []
    for j in range(Uo.shape[1]):
        H = dense(model.constraint_hessian(q, Uo[:, j], dense=True))
        h = float(np.linalg.norm(H, 2)) or 1.0
        changes.append((N.T @ H @ N).ravel() / h)
    C = np.array(changes).T  # columns: the change per state
    if not C.size:
        return out
    Uc, sc, Vct = np.linalg.svd(C, full_matrices=False)
    for j in range(sc.size):
        if sc[j] <= tol:
            continue
        mu = Uo @ Vct[j]
        mu /= np.linalg.norm(mu)
        loaded = sorted({names[i] for i in np.flatnonzero(np.abs(mu) > 1e-3 * np.abs(mu).max())})
        out.append({"constraints": loaded, "mu": mu, "stiffness_change": float(sc[j])})
    return out


def _force_per_multiplier(c, q):
    """d(reaction)/dλ of a one-row element (the reaction is linear in λ), as a norm."""
    cols = []
    for k in range(c.n_eq):
        e = np.zeros(c.n_eq)
        e[k] = 1.0
        v = c.reaction(q, e)["value"]
        cols.append(np.atleast_1d(np.asarray(v, dtype=float)))
    return np.column_stack(cols)


def compliant_multipliers(model, q, lam, compliance: dict, *, rank_tol=1e-10):
    """λ of least complementary energy ½ Σ c_k |N_k(λ)|² among λ + span(self-stress states),
    with ``compliance`` = {constraint name: c} (the element's extension per unit of the force
    it reports, e.g. m/N for a rod).  Returns (λ, the states the compliance leaves
    undetermined, as columns)."""
    _, Uo, _, _ = _basis(model, q, rank_tol)
    if Uo.shape[1] == 0:
        return lam, Uo
    m = model.n_constraints
    W = np.zeros((m, m))
    k = 0
    for c in model.constraints:
        cval = compliance.get(c.name)
        if cval is not None:
            B = _force_per_multiplier(c, q)
            W[k:k + c.n_eq, k:k + c.n_eq] = float(cval) * (B.T @ B)
        k += c.n_eq
    G = Uo.T @ W @ Uo
    u, sv, vt = np.linalg.svd(G)
    keep = sv > 1e-12 * max(float(sv.max(initial=0.0)), 1e-300)
    t = -(vt[keep].T @ ((u[:, keep].T @ (Uo.T @ W @ lam)) / sv[keep]))
    return lam + Uo @ t, Uo @ vt[~keep].T
