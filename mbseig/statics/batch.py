"""The equilibria of many models at once: Newton on all points of a line together.

For the B models of a :class:`~mbseig.model.stacked.ModelStack` the branch equations of
:class:`~mbseig.statics.family.Family` (y = (q, λ on the followed rows)),

    R(y) = [g(q) − Φ_q(q)[rows]ᵀ λ ;  −Φ(q)[rows]],     S(y) = [[K + H(λ), Φ_qᵀ], [Φ_q, 0]],

are solved by the corrector of a continuation (:func:`mbseig.statics.branch.correct_fixed`'s
plain Newton: y ← y + S⁻¹R while the corrections shrink, converged at a correction below
``CTOL`` in the model's scales), with S and R of all points formed and solved as stacked arrays.
Each point stops when it converges; a point whose corrections stop shrinking is left
unconverged (its reason recorded), never guessed.

:func:`static_verdicts` gives the static stability of every point by the rule of
:func:`mbseig.statics.stiffness.static_stability` (symmetric K_r: eigenvalues against
``stiffness_tol``·‖K_r‖₂; otherwise the real eigenvalues' count and sign), with the same record.
"""

from __future__ import annotations

import numpy as np

from .family import CORRECTOR_ITER, CTOL
from .result import StaticStability
from .stiffness import STIFFNESS_TOL, SYMMETRY_TOL

__all__ = ["newton_batch", "static_verdicts", "null_bases", "singular", "SINGULAR"]


def _size(scales, dQ):
    """:meth:`StepScales.size` of every row of dQ (B, n)."""
    s = np.max(np.abs(dQ) / scales.ell, axis=1, initial=0.0)
    if scales.D is not None:
        dd = (scales.D @ dQ.T).T * scales.inv_len
        k = scales.dims
        if k > 1:
            rot = np.sqrt(np.add.reduceat(dd * dd, np.arange(0, dd.shape[1], k), axis=1))
        else:
            rot = np.abs(dd)
        s = np.maximum(s, np.max(rot, axis=1, initial=0.0))
    return s


def residual(stack, Y, rows):
    """R (B, n + |rows|) and S (B, N, N) of the branch equations at Y."""
    n = stack.n
    Q, lam = Y[:, :n], Y[:, n:]
    G = stack.g(Q)
    if not rows.size:
        K, _ = stack.jacobians(Q)
        return G, K
    J = stack.phi_q(Q)[:, rows]
    Lf = np.zeros((Y.shape[0], stack.m))
    Lf[:, rows] = lam
    R = np.concatenate([G - np.einsum("bkn,bk->bn", J, lam), -stack.phi(Q)[:, rows]], axis=1)
    K, _ = stack.jacobians(Q)
    A = K + stack.hessian(Q, Lf)
    r = rows.size
    S = np.zeros((Y.shape[0], n + r, n + r))
    S[:, :n, :n] = A
    S[:, :n, n:] = np.swapaxes(J, 1, 2)
    S[:, n:, :n] = J
    return R, S


#: a Newton matrix whose smallest singular value is below this times its largest is singular
#: (a free rotation, a mechanism at rest in neutral equilibrium): minimum-norm steps
SINGULAR = 1e-12


def singular(S):
    """Whether the stacked Newton matrices S (B, N, N) are numerically singular (any of them)."""
    sv = np.linalg.svd(S, compute_uv=False)
    return bool(np.any(sv[:, -1] <= SINGULAR * sv[:, 0]))


def _null_border(Sw):
    """(Z, Y): orthonormal right and left null bases of the first matrix of Sw (its singular
    vectors at singular values ≤ SINGULAR·σ_max), or None where it has none."""
    U, s, Vt = np.linalg.svd(Sw[0])
    k = int(np.sum(s <= SINGULAR * s[0])) if s[0] > 0 else 0
    if not k or k == s.size:
        return None
    return Vt[-k:].T, U[:, -k:]


def _bordered(Sw, R, border):
    """The minimum-norm least-squares solutions z = Sw⁺R of the points whose matrices have the
    null spaces ``border`` = (Z, Y) (the first point's, :func:`_null_border`), NaN rows for the
    others.  A point qualifies when ‖Sw Z‖_F and ‖Yᵀ Sw‖_F are at most SINGULAR·‖Sw‖_F/√N: then
    ‖Sw Z‖₂ ≤ SINGULAR·‖Sw‖₂, so Z spans singular directions that the pseudo-inverse's cut-off
    drops.  The bordered system [[Sw, Y], [Zᵀ, 0]] [z; μ] = [R; 0] then gives μ = YᵀR and
    Sw z = R − YYᵀR with Zᵀz = 0: the projection of R on the range of Sw, solved orthogonally to
    the null space, which is Sw⁺R (one LU solve instead of an SVD) where the other singular
    values lie above the cut-off.  A solution with ‖z‖·SINGULAR·‖Sw‖_F/√N ≥ ‖R‖ may hold a
    singular value of its own at the cut (‖z‖ ≤ ‖R‖/σ of the kept ones): that point gets NaN
    too, and so the pseudo-inverse."""
    Z, Y = border
    B, N, _ = Sw.shape
    k = Z.shape[1]
    lim = SINGULAR * np.sqrt((Sw * Sw).sum(axis=(1, 2)) / N)
    ok = ((np.sqrt(((Sw @ Z) ** 2).sum(axis=(1, 2))) <= lim)
          & (np.sqrt(((Y.T @ Sw) ** 2).sum(axis=(1, 2))) <= lim))
    out = np.full((B, N), np.nan)
    idx = np.flatnonzero(ok)
    if idx.size:
        A = np.zeros((idx.size, N + k, N + k))
        A[:, :N, :N] = Sw[idx]
        A[:, :N, N:] = Y
        A[:, N:, :N] = Z.T
        rhs = np.zeros((idx.size, N + k, 1))
        rhs[:, :N, 0] = R[idx]
        try:
            z = np.linalg.solve(A, rhs)[:, :N, 0]
        except np.linalg.LinAlgError:  # one singular bordered matrix: all by the pseudo-inverse
            return out
        small = (np.linalg.norm(z, axis=1) * lim[idx] < np.linalg.norm(R[idx], axis=1)) \
            | ~np.any(R[idx], axis=1)
        out[idx[small]] = z[small]
    return out


def _steps(S, R, weights, min_norm, border=None):
    """S⁻¹R per point; with ``min_norm`` the minimum-norm solution in the scaled unknowns
    (y = w z: the step is smallest in lengths of the model, as the statics' own Newton takes it
    on a singular matrix): by the bordered solve of :func:`_bordered` where a point's matrix has
    the null spaces ``border``, else by the stacked pseudo-inverse."""
    if min_norm:
        Sw = S * weights[None, None, :]
        z = (np.full(R.shape, np.nan) if border is None else _bordered(Sw, R, border))
        bad = np.flatnonzero(~np.all(np.isfinite(z), axis=1))
        if bad.size:
            z[bad] = np.einsum("bij,bj->bi", np.linalg.pinv(Sw[bad], rcond=SINGULAR), R[bad])
        return z * weights
    try:
        return np.linalg.solve(S, R[:, :, None])[:, :, 0]
    except np.linalg.LinAlgError:  # one singular S stops the stacked solve: each alone
        dY = np.full_like(R, np.nan)
        for j in range(R.shape[0]):
            try:
                dY[j] = np.linalg.solve(S[j], R[j])
            except np.linalg.LinAlgError:
                pass
        return dY


def newton_batch(stack, Y0, rows, scales, *, max_iter=CORRECTOR_ITER, tol=CTOL, active=None,
                 min_norm=False):
    """Newton on every point from Y0 (B, n + |rows|) (module docstring); ``active``: the points
    to solve (default all; the others keep their Y0); ``min_norm``: minimum-norm steps (the
    Newton matrices are singular: :func:`singular`).

    Returns (Y, iterations (B,), converged (B,) bool, last correction (B,))."""
    Y = np.array(Y0, float)
    B = Y.shape[0]
    its = np.zeros(B, int)
    last = np.full(B, np.inf)
    active = np.ones(B, bool) if active is None else np.array(active, bool)
    done = np.zeros(B, bool)
    weights = np.concatenate([scales.ell, np.ones(Y.shape[1] - stack.n)])  # (λ: unscaled)
    border = None  # the null spaces of the first Newton matrix (minimum-norm steps)
    with np.errstate(all="ignore"):
        for it in range(1, max_iter + 1):
            idx = np.flatnonzero(active)
            if not idx.size:
                break
            sub = stack if idx.size == B else stack.take(idx)
            R, S = residual(sub, Y[idx], rows)
            if min_norm and border is None:
                border = _null_border(S[:1] * weights[None, None, :]) or False
            dY = _steps(S, R, weights, min_norm, border or None)
            size = _size(scales, dY[:, :stack.n])
            grow = ~np.isfinite(size) | (size >= last[idx])
            ok = ~grow
            Y[idx[ok]] += dY[ok]
            its[idx[ok]] = it
            last[idx[ok]] = size[ok]
            conv = ok & (size <= tol)
            done[idx[conv]] = True
            active[idx[conv | grow]] = False
    return Y, its, done, last


def null_bases(Phi_q, rank_tol=1e-10):
    """(N (B, n, n − r), rank r) of stacked dense Φ_q (B, m, n) of one rank: the right singular
    vectors beyond the rank (the rank rule of :func:`mbseig.statics.stiffness._basis`); None
    where the points' ranks differ."""
    B, m, n = Phi_q.shape
    if m == 0:
        return np.broadcast_to(np.eye(n), (B, n, n)), 0
    _, s, Vt = np.linalg.svd(Phi_q, full_matrices=True)
    ranks = np.sum(s > rank_tol * s[:, :1], axis=1)
    if not np.all(ranks == ranks[0]):
        return None
    r = int(ranks[0])
    return np.swapaxes(Vt[:, r:, :], 1, 2), r


def static_verdicts(Kr, N, *, stiffness_tol=STIFFNESS_TOL, symmetry_tol=SYMMETRY_TOL):
    """The :class:`StaticStability` of each point from its reduced stiffness Kr (B, d, d) and
    basis N (B, n, d), by the rule of :func:`mbseig.statics.stiffness.static_stability`."""
    B, d, _ = Kr.shape
    base = {"dof": int(d), "stiffness_tol": stiffness_tol, "symmetry_tol": symmetry_tol}
    if d == 0:
        rec = StaticStability(**base, verdict="stable", index=0, symmetric=True,
                              min_eigenvalue=None, direction=None)
        return [rec] * B
    norm = np.linalg.norm(Kr, 2, axis=(1, 2))
    norm = np.where(norm > 0, norm, 1.0)
    S = Kr - np.swapaxes(Kr, 1, 2)
    asym = np.where(S.any(axis=(1, 2)), np.linalg.norm(S, 2, axis=(1, 2)) / norm, 0.0)
    sym = asym <= symmetry_tol
    out = [None] * B
    if sym.any():
        i = np.flatnonzero(sym)
        mu, V = np.linalg.eigh(0.5 * (Kr[i] + np.swapaxes(Kr[i], 1, 2)))
        t = stiffness_tol * norm[i][:, None]
        index = np.sum(mu < -t, axis=1)
        zero = np.sum(np.abs(mu) <= t, axis=1)
        direction = np.einsum("bnd,bd->bn", N[i], V[:, :, 0])
        for j, b in enumerate(i):
            out[b] = StaticStability(
                **base, symmetric=True, asymmetry=float(asym[b]),
                min_eigenvalue=float(mu[j, 0]), index=int(index[j]), zero=int(zero[j]),
                direction=direction[j],
                verdict="unstable" if index[j] else ("neutral" if zero[j] else "stable"))
    if (~sym).any():
        i = np.flatnonzero(~sym)
        mu, V = np.linalg.eig(Kr[i])
        t = stiffness_tol * norm[i][:, None]
        real = np.abs(mu.imag) <= t
        index = np.sum(real & (mu.real < -t), axis=1)
        zero = np.sum(np.abs(mu) <= t, axis=1)
        any_real = real.any(axis=1)
        k = np.argmin(np.where(real, mu.real, np.inf), axis=1)
        positive = np.all(mu.real > t, axis=1)
        vk = np.take_along_axis(V, k[:, None, None], axis=2)[:, :, 0].real
        direction = np.einsum("bnd,bd->bn", N[i], vk)
        for j, b in enumerate(i.tolist()):
            ix, zr = int(index[j]), int(zero[j])
            verdict = ("unstable" if ix % 2 == 1 and not zr else
                       "undetermined" if ix or zr else
                       "stable" if positive[j] else "undetermined")
            found = bool(any_real[j])
            out[b] = StaticStability(
                **base, symmetric=False, asymmetry=float(asym[b]),
                min_eigenvalue=float(mu[j, k[j]].real) if found else None, index=ix, zero=zr,
                direction=direction[j] if found else None, verdict=verdict)
    return out
