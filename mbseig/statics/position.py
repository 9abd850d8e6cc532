"""The position solve: the point on Φ(q) = 0 nearest q, without forces (docs/design.md,
"Equilibrium").

Levenberg–Marquardt on ½‖Φ/scale‖² in the scaled coordinates q_i/ℓ_i (each constraint row
divided by its own scale): minimum-norm Gauss–Newton steps where the constraints are
consistent, damped where they are not, each bounded by the trust radius in the model's length
and angle scales (:class:`~mbseig.statics.linalg.StepScales`).
It is the first stage of every equilibrium and the projection after every Newton step.

When the iteration stops at a stationary point of ‖Φ/scale‖² with Φ ≠ 0 (the scaled gradient
Jᵀ(Φ/scale) below ``STATIONARY`` relative to ‖J‖‖Φ/scale‖), no nearby position satisfies the
constraints: :class:`~mbseig.statics.failures.ConstraintsUnsatisfiable`, naming the constraint
with the largest relative residual.  That is the only place that error is raised.
"""

from __future__ import annotations

import numpy as np

from .failures import ConstraintsUnsatisfiable

__all__ = ["position_solve", "constraint_residual", "STATIONARY"]

STATIONARY = 1e-7  # relative gradient of ‖Φ/scale‖² at which the position solve has stalled


def constraint_residual(model, q, cscale):
    """(Φ(q), max_k |Φ_k|/scale_k)."""
    phi = model.phi(q)
    with np.errstate(all="ignore"):
        rel = float(np.max(np.abs(phi) / cscale, initial=0.0)) if phi.size else 0.0
    return phi, (rel if np.isfinite(rel) else np.inf)


def position_solve(model, q, scales, *, tol, max_iter=100, radius=0.5, prove=True):
    """(q on Φ = 0 to ``tol``, iterations) or (None, iterations) when it does not get there.

    Levenberg–Marquardt on ½‖Φ/scale‖² in the scaled coordinates q_i/ℓ_i, in its dual form
    z = −Jᵀ(J Jᵀ + μ I)⁻¹ r (the minimum-norm Gauss–Newton step as μ → 0, so a consistent
    system converges quadratically; at a least-squares minimum with Φ ≠ 0 the damping keeps it
    from zigzagging across the singular directions), μ adapted by the gain ratio (Nielsen), the
    step bounded by ``radius`` in the model's scales.

    prove : when the iteration stops at a least-squares minimum with Φ ≠ 0, raise
        :class:`ConstraintsUnsatisfiable` (the first position solve); otherwise return None
        (a projection after a Newton step: the caller shortens the step).
    """
    m = model.n_constraints
    if m == 0:
        return q, 0
    cscale = model.constraint_scales()
    phi, rel = constraint_residual(model, q, cscale)
    mu, nu = None, 2.0
    for it in range(max_iter + 1):
        if rel <= tol:
            return q, it
        if it == max_iter or not np.isfinite(rel):
            break
        r = phi / cscale
        Js = _scaled_jacobian(model, q, cscale, scales)
        rr = float(r @ r)
        if mu is None:  # Yamashita–Fukushima: μ ∝ ‖r‖², relative to ‖J‖²
            mu = 1e-3 * min(1.0, rr) * max(float(np.max(np.abs(_values(Js)), initial=0.0)) ** 2,
                                            1e-300)
        accepted = False
        for _ in range(60):
            z = _lm_step(Js, r, mu)
            dq = scales.ell * z
            size = scales.size(dq)
            if size > radius:
                dq, z = dq * (radius / size), z * (radius / size)
            qt = q + dq
            try:
                phit, relt = constraint_residual(model, qt, cscale)
            except ArithmeticError:
                relt = np.inf
            if np.isfinite(relt):
                rt = phit / cscale
                lin = r + Js @ z
                pred = rr - float(lin @ lin)
                gain = (rr - float(rt @ rt)) / pred if pred > 0 else -1.0
            else:
                gain = -1.0
            if gain > 0:
                mu *= max(1.0 / 3.0, 1.0 - (2.0 * gain - 1.0) ** 3)
                nu = 2.0
                accepted = True
                break
            mu *= nu
            nu *= 2.0
        if not accepted:
            break
        stalled = float(rt @ rt) > 0.81 * rr  # less than 10 % off ‖Φ/scale‖ in this step
        q, phi, rel = qt, phit, relt
        if prove and stalled and rel > tol and _stationary(model, q, phi, cscale, scales):
            raise _unsatisfiable(model, phi, cscale, it + 1)
    if prove and rel > tol and _stationary(model, q, phi, cscale, scales):
        raise _unsatisfiable(model, phi, cscale, max_iter)
    return None, max_iter


def _scaled_jacobian(model, q, cscale, scales):
    import scipy.sparse as sp

    Phi_q = model.phi_q(q)
    if not sp.issparse(Phi_q):  # a small model's dense Jacobian (mbseig.statics.cache.Memo)
        return Phi_q * (1.0 / cscale)[:, None] * scales.ell[None, :]
    return (sp.diags(1.0 / cscale) @ Phi_q @ sp.diags(scales.ell)).tocsr()


def _values(Js):
    """The stored values of Js (its nonzeros when sparse, every entry when dense)."""
    import scipy.sparse as sp

    return sp.csr_matrix(Js).data if sp.issparse(Js) else np.ravel(Js)


def _lm_step(Js, r, mu):
    """z = −Jsᵀ (Js Jsᵀ + μ I)⁻¹ r (dense up to 300 rows, sparse LU above)."""
    import scipy.linalg as sla
    import scipy.sparse as sp

    m = Js.shape[0]
    G = Js @ Js.T
    with np.errstate(all="ignore"):
        try:
            if m <= 300:
                A = G.toarray() if sp.issparse(G) else np.array(G)
                A[np.diag_indices(m)] += mu
                try:
                    w = sla.solve(A, r, assume_a="pos")
                except sla.LinAlgError:
                    w = sla.lstsq(A, r)[0]
            else:
                import scipy.sparse.linalg as spla  # large models only: off the start-up path

                w = spla.splu((G + mu * sp.identity(m)).tocsc()).solve(r)
        except (ValueError, RuntimeError, sla.LinAlgError):  # not finite, or singular
            return np.zeros(Js.shape[1])
    return -(Js.T @ w)


def _stationary(model, q, phi, cscale, scales):
    """Whether ‖Φ/scale‖² is stationary at q: |Jsᵀ r| ≤ STATIONARY ‖Js‖ ‖r‖ (scaled)."""
    r = phi / cscale
    Js = _scaled_jacobian(model, q, cscale, scales)
    grad = Js.T @ r
    nJ = float(np.linalg.norm(_values(Js)))  # ‖Js‖_F
    return float(np.linalg.norm(grad)) <= STATIONARY * nJ * float(np.linalg.norm(r))


def _unsatisfiable(model, phi, cscale, iterations):
    rel = np.abs(phi) / cscale
    k = int(np.argmax(rel))
    name = model.constraint_row_names()[k]
    others = sorted({model.constraint_row_names()[i] for i in np.flatnonzero(rel > 0.1 * rel[k])}
                    - {name})
    also = f" (also off: {', '.join(others[:3])})" if others else ""
    return ConstraintsUnsatisfiable(
        f"the constraints cannot be satisfied: the position solve of Φ = 0 alone stops at a "
        f"least-squares minimum after {iterations} iterations with this constraint off by "
        f"{rel[k]:.3g} of its scale{also}", element=name)
