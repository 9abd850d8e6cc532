"""Accuracy measures of the fused small-dense implementation (:mod:`mbseig.eigen.small`):
η, κ and the componentwise pair by the formulas of :mod:`mbseig.eigen.measures` on one block of
rows, every quantity the eigenvalues share (the reversal t = 1/s, the coefficients of M, P, Q,
the weights w(s)) formed once, the two halves of the companion vectors side by side."""

from __future__ import annotations

import numpy as np

from .measures import colnorm, fixed_zero, unit_columns

__all__ = ["cn", "unit", "coefficients", "ratio", "better_half", "conditions",
           "componentwise_small"]


def fast_norms(X):
    """Column 2-norms by the fast evaluation of :func:`mbseig.eigen.measures.colnorm`."""
    if X.dtype.kind == "c":
        Xr, Xi = X.real, X.imag
        return np.sqrt(np.einsum("ij,ij->j", Xr, Xr) + np.einsum("ij,ij->j", Xi, Xi))
    return np.sqrt(np.einsum("ij,ij->j", X, X))


def plain(nrm):
    """Norms in the range where the fast evaluation is colnorm's own (every entry of the
    column within 1e±150, none of the squares lost)."""
    return not nrm.size or (1e-140 <= nrm.min() and nrm.max() <= 1e140)


def cn(X):
    """Column 2-norms as :func:`mbseig.eigen.measures.colnorm` gives them."""
    nrm = fast_norms(X)
    return nrm if plain(nrm) else colnorm(X)


def unit(X):
    """X with unit columns, as :func:`mbseig.eigen.measures.unit_columns` gives it."""
    nrm = fast_norms(X)
    return X / nrm if plain(nrm) else unit_columns(X)


def coefficients(s, norms=None):
    """What every measure of the eigenvalues s shares, formed once: the reversal t = 1/s where
    |s| > 1 (``big``), the coefficients of M, P, Q in the (reversed) polynomial and in its
    derivative, and with ``norms`` the weights w(s) (:mod:`mbseig.eigen.measures`); np.where's
    choices without np.where where every |s| lies on one side of 1."""
    big = np.abs(s) > 1.0
    low = not big.any()
    high = not low and big.all()
    if low:
        t = s.copy()
        one = np.ones_like(t)
        co = {"cM": t * t, "cQ": one, "dM": 2.0 * t, "dP": one}
    elif high:
        t = 1.0 / s
        one = np.ones_like(t)
        co = {"cM": one, "cQ": t * t, "dM": np.full(t.shape, 2.0 + 0j), "dP": t}
    else:
        t = np.where(big, 1.0 / np.where(big, s, 1.0), s)
        one = np.ones_like(t)
        tt = t * t
        co = {"cM": np.where(big, one, tt), "cQ": np.where(big, tt, one),
              "dM": np.where(big, 2.0, 2.0 * t), "dP": np.where(big, t, one)}
    co["big"], co["t"] = big, t
    if norms is not None:
        nM, nP, nQ = norms
        a = np.abs(t)
        if low:
            co["w"] = a * a * nM + a * nP + nQ
        elif high:
            co["w"] = nM + a * nP + a * a * nQ
        else:
            co["w"] = np.where(big, nM + a * nP + a * a * nQ, a * a * nM + a * nP + nQ)
    return co


def ratio(num, den):
    """measures' num/den with 0/0 = 0 and x/0 = ∞ (a quotient beyond the double range raises
    under the fused path's floating-point state: the general path then runs)."""
    pos = den > 0
    return np.where(pos, num / np.where(pos, den, 1.0), np.where(num == 0, 0.0, np.inf))


def better_half(M, P, Q, X1, X2, co):
    """measures.better_half: η of both halves of the companion vectors, the better kept; the
    halves side by side, so that every product and norm is one call for both (``co``: the
    coefficients of the eigenvalues repeated for the second half)."""
    k = X1.shape[1]
    Xs = unit(np.concatenate([X1, X2], axis=1))
    if k >= 2:  # (a single column is a matrix-vector product: kept as the general driver's)
        MX, PX, QX = M @ Xs, P @ Xs, Q @ Xs
    else:
        MX, PX, QX = (np.concatenate([A @ Xs[:, :1], A @ Xs[:, 1:]], axis=1) for A in (M, P, Q))
    R = MX * co["cM"]
    R += PX * co["t"]
    R += QX * co["cQ"]
    rn, xn = cn(R), cn(Xs)
    eta = np.where(xn > 0, ratio(rn, co["w"] * xn), np.inf)
    e1, e2 = eta[:k], eta[k:]
    take2 = e2 < e1
    if not take2.any():
        def first(A):
            return np.ascontiguousarray(A[:, :k])

        return first(Xs), np.minimum(e1, e2), first(MX), first(PX), 0

    def pick(A):
        return np.where(take2, A[:, k:], A[:, :k])

    return pick(Xs), np.minimum(e1, e2), pick(MX), pick(PX), int(take2.sum())


def conditions(s, X, Yc, MX, PX, co):
    """measures.conditions on one block of rows, the shared coefficients given."""
    nx = cn(X)
    num = co["w"] * nx * (nx if Yc is X else cn(Yc))
    den = np.abs(np.einsum("ij,ij->j", Yc, MX * co["dM"] + PX * co["dP"]))
    kappa = ratio(num, den)
    if co["big"].any():
        kappa = np.where(co["big"], kappa * np.abs(s), kappa)
    return fixed_zero(np.where(den > 0, kappa, np.inf), co["w"])


def componentwise_small(sol, idx):
    """(η_c, κ_c) of the pairs ``idx`` of a fused solution: :meth:`QEPSolution.componentwise`
    (:func:`mbseig.eigen.measures.componentwise`) on one block of rows."""
    M, P, Q, gamma = sol.problem
    X = np.ascontiguousarray(sol.vectors[:, idx])
    Yc = X if sol.left_vectors is None else sol.left_vectors[:, idx]
    s = sol.eigenvalues[idx]
    mu = s.real / gamma + 1j * (s.imag / gamma)
    co = coefficients(mu)
    a = np.abs(co["t"])
    MX, PX = M @ X, P @ X
    R = MX * co["cM"]
    R += PX * co["t"]
    R += (Q @ X) * co["cQ"]
    R = np.abs(R)
    AX = np.abs(X)
    AMX, APX, AQX = np.abs(M) @ AX, np.abs(P) @ AX, np.abs(Q) @ AX
    aa = a * a
    D = np.where(co["big"], AMX + APX * a + AQX * aa, AMX * aa + APX * a + AQX)
    eta_c = np.max(ratio(R, D), axis=0, initial=0.0)
    num = np.einsum("ij,ij->j", np.abs(Yc), D)
    den = np.abs(np.einsum("ij,ij->j", Yc, MX * co["dM"] + PX * co["dP"]))
    kappa_c = ratio(num, den)
    if co["big"].any():
        kappa_c = np.where(co["big"], kappa_c * np.abs(mu), kappa_c)
    kappa_c = np.where(den > 0, kappa_c, np.inf)
    kappa_c = np.where((den == 0) & (num == 0), 0.0, kappa_c)
    return eta_c, kappa_c * gamma
