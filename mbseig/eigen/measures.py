"""Structure tests and accuracy measures of eigenpairs, for dense and sparse M, P, Q alike.

Backward error of a pair (s, x) (Tisseur 2000, Frobenius-norm weights)::

    η = ‖(s²M + sP + Q)x‖ / (w(s) ‖x‖),    w(s) = |s|²‖M‖ + |s|‖P‖ + ‖Q‖

Absolute condition number from the left vector y (yᴴ(s²M + sP + Q) = 0)::

    κ = w(s) ‖x‖ ‖y‖ / |yᴴ(2sM + P)x|

so that κ·η bounds the error of s to first order (docs/design.md, "Eigenpair errors").
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ..numerics import colnorm, unit_columns

__all__ = ["EPS", "fro", "is_symmetric", "rayleigh_fit", "backward_errors", "conditions",
           "better_half", "undamped_roots", "undamped_pairs", "proportional_real_error"]

EPS = np.finfo(float).eps


def fro(A) -> float:
    """Frobenius norm of a dense or sparse matrix."""
    if sp.issparse(A):
        return float(spla.norm(A)) if A.nnz else 0.0
    return float(np.linalg.norm(A))


def is_symmetric(A, tol) -> bool:
    """‖A − Aᵀ‖_F ≤ tol ‖A‖_F (a zero matrix is symmetric)."""
    nA = fro(A)
    return nA == 0 or fro(A - A.T) <= tol * nA


def rayleigh_fit(M, P, Q, tol, *, probes=None, seed=0):
    """(α, β) with P = αM + βQ to relative accuracy ``tol``, or None.

    Dense matrices are fitted entry by entry; with ``probes`` = k the fit uses the products with
    k random vectors instead (sparse matrices, never densified).
    """
    if fro(P) == 0:
        return 0.0, 0.0
    if probes is None:
        cols, b = [M.ravel(), Q.ravel()], P.ravel()
    else:
        V = np.random.default_rng(seed).standard_normal((M.shape[0], probes))
        cols, b = [(M @ V).ravel(), (Q @ V).ravel()], (P @ V).ravel()
    A = np.column_stack(cols)
    coef, *_ = np.linalg.lstsq(A, b, rcond=None)
    if np.linalg.norm(A @ coef - b) <= tol * np.linalg.norm(b):
        return float(coef[0]), float(coef[1])
    return None


def _weights(s, norms):
    nM, nP, nQ = norms
    return np.abs(s) ** 2 * nM + np.abs(s) * nP + nQ


def backward_errors(ops, s, X, norms):
    """(η, M X, P X): backward errors and the products reused for the condition numbers.

    A pair with zero residual has η = 0 even where the weights vanish (s = 0 with Q = 0).
    """
    M, P, Q = ops
    MX, PX = M @ X, P @ X
    R = MX * s  # Horner: (M X s + P X) s + Q X
    R = R + PX
    R = R * s
    R = R + Q @ X
    rn = colnorm(R)
    denom = _weights(s, norms) * colnorm(X)
    with np.errstate(divide="ignore", invalid="ignore"):
        eta = np.where(denom > 0, rn / denom, np.where(rn == 0, 0.0, np.inf))
    return eta, MX, PX


def conditions(s, X, Yc, MX, PX, norms):
    """κ per pair, with ``Yc`` the conjugated left vectors (yᴴ = Ycᵀ) and MX, PX the products."""
    num = _weights(s, norms) * colnorm(X) * colnorm(Yc)
    den = np.abs(np.einsum("ij,ij->j", Yc, MX * (2 * s) + PX))
    with np.errstate(divide="ignore", invalid="ignore"):
        kappa = num / den
    return np.where(den > 0, kappa, np.inf)


def better_half(ops, s, X1, X2, norms):
    """Of the two halves of companion eigenvectors, the one with the smaller η per column.

    Returns (X, η, M X, P X, number of columns taken from the second half), X with unit columns.
    """
    X1, X2 = np.ascontiguousarray(unit_columns(X1)), np.ascontiguousarray(unit_columns(X2))
    e1, MX1, PX1 = backward_errors(ops, s, X1, norms)
    e2, MX2, PX2 = backward_errors(ops, s, X2, norms)
    take2 = e2 < e1
    for a, b in ((X1, X2), (MX1, MX2), (PX1, PX2)):
        a[:, take2] = b[:, take2]
    return X1, np.minimum(e1, e2), MX1, PX1, int(np.sum(take2))


def undamped_roots(w, alpha, beta):
    """Both roots of s² + (α + βω²)s + ω² = 0 per undamped mode ω² = w, [s₊; s₋] (stable form)."""
    c = alpha + beta * w
    disc = c * c - 4.0 * w
    s1 = np.empty(w.size, complex)
    s2 = np.empty(w.size, complex)
    osc = disc < 0
    s1[osc] = -c[osc] / 2 + 0.5j * np.sqrt(-disc[osc])
    s2[osc] = np.conj(s1[osc])
    re = ~osc
    root = np.sqrt(disc[re])
    cr = c[re]
    big = -(cr + np.copysign(root, cr)) / 2  # the root of larger magnitude, no cancellation
    small = np.divide(w[re], big, out=np.zeros_like(big), where=big != 0)
    s1[re], s2[re] = big, small
    return np.concatenate([s1, s2])


def undamped_pairs(M, P, Q, w, V, alpha, beta, norms):
    """s₊, s₋ of each undamped mode (ω², v) with s² + (α + βω²)s + ω² = 0; η and κ in real
    arithmetic on the n real vectors (M, P, Q symmetric: y = x, κ = w(s)‖v‖²/|2s vᵀMv + vᵀPv|).

    Returns (s, X, η, κ) with s = [s₊, s₋] and X = [V, V] (real, unit columns).
    """
    s = undamped_roots(w, alpha, beta)
    V = V / colnorm(V)
    MV, PV, QV = M @ V, P @ V, Q @ V
    a, b = np.einsum("ij,ij->j", V, MV), np.einsum("ij,ij->j", V, PV)
    k = w.size
    rn = np.empty(2 * k)
    for half in (slice(0, k), slice(k, 2 * k)):  # s₊ then s₋, both with the vectors V
        sh = s[half]
        s2 = sh * sh
        Rr = MV * s2.real + PV * sh.real + QV
        Ri = MV * s2.imag + PV * sh.imag
        rn[half] = np.sqrt(np.einsum("ij,ij->j", Rr, Rr) + np.einsum("ij,ij->j", Ri, Ri))
        del Rr, Ri
    weight = _weights(s, norms)
    with np.errstate(divide="ignore", invalid="ignore"):
        eta = np.where(weight > 0, rn / weight, np.where(rn == 0, 0.0, np.inf))
        den = np.abs(2 * s * np.concatenate([a, a]) + np.concatenate([b, b]))
        kappa = np.where(den > 0, weight / den, np.inf)
    return s, np.concatenate([V, V], axis=1), eta, kappa


def proportional_real_error(s, kappa, eta, norms, alpha, beta, fit_residual):
    """Error bound of Re s on the proportional path, oscillatory roots (Re s = −(α + βω²)/2).

    ω² = −s s̄ for the pair; its error is at most 2|s|·κη (first order, undamped pencil), so
    |Δ Re s| ≤ |β| |s| κη + κ |s| ‖P − αM − βQ‖ / w(s) + ε |α + βω²|, w(s) the η weight.
    Real (overdamped) roots get no bound here (κη applies).
    """
    weight = _weights(s, norms)
    ke = kappa * np.maximum(eta, EPS)
    with np.errstate(divide="ignore", invalid="ignore"):
        fit = np.where(weight > 0, kappa * np.abs(s) * fit_residual / weight, np.inf)
    err = np.abs(beta) * np.abs(s) * ke + fit + EPS * 2 * np.abs(s.real)
    return np.where(np.abs(s.imag) > 0, err, np.inf)
