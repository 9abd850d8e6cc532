"""Error bounds, tolerances and stabilities of many problems at once (the points of a sweep).

:func:`batch_tolerances` gives, for every problem of a :class:`~mbseig.eigen.batch.BatchSolution`,
what :func:`mbseig.modal.bounds.tolerances` gives for one: the error bound of every eigenvalue
(first order κη; componentwise where that does not separate s from 0, from the real axis or from
its neighbours; a cluster's bound for eigenvalues that lie within each other's reach, with the
Hölder radius of a defective block), the tolerance τ = max(safety·err, rtol·|s|, atol), the
rigid-body test |s| ≤ τ with the zero-pair floor, and the stability of each mode by the one rule
of :mod:`mbseig.modal.rules`.  The neighbour searches of the one-point code (a k-d tree) are
here the (B, k, k) matrix of distances |s_i − s_j|, and its connected components a boolean
closure: the same sets, computed for all problems by a few array operations.  The few quantities
that need a problem of their own (the rank of a cluster's vectors, the nullity of T(s̄) of a
rank-deficient cluster) are computed by :mod:`mbseig.modal.bounds`' own functions for those
clusters alone.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..eigen import EPS
from ..eigen.small_measures import coefficients, ratio
from .bounds import nullities, numerical_ranks

__all__ = ["BatchBounds", "batch_tolerances", "STABLE", "CRITICAL", "UNSTABLE", "WORDS"]

STABLE, CRITICAL, UNSTABLE = 0, 1, 2
WORDS = np.array(["stable", "critical", "unstable"], dtype=object)


@dataclass
class BatchBounds:
    """Per problem b and eigenvalue j: err, tol, tol_re (B, k); rigid (B, k) bool; stability
    (B, k) codes (STABLE, CRITICAL, UNSTABLE; WORDS[code] is the word); cluster and block
    (B, k) ints as :class:`~mbseig.modal.bounds.Bounds` holds them."""

    err: np.ndarray
    tol: np.ndarray
    tol_re: np.ndarray
    rigid: np.ndarray
    stability: np.ndarray
    cluster: np.ndarray
    block: np.ndarray


def _frequency_scale(norms):
    nM, nP, nQ = norms.T
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where((nM > 0) & (nQ > 0), np.sqrt(nQ / np.where(nM > 0, nM, 1.0)),
                        np.where((nM > 0) & (nP > 0), nP / np.where(nM > 0, nM, 1.0),
                                 np.where((nP > 0) & (nQ > 0), nQ / np.where(nP > 0, nP, 1.0),
                                          1.0)))


def _componentwise(M, P, Q, s, X, Yc):
    """(η_c, κ_c) of every pair: :func:`mbseig.eigen.small_measures.componentwise_small`
    (unscaled problems, γ = 1) with a batch axis."""
    co = coefficients(s)
    a = np.abs(co["t"])[:, None, :]
    big = co["big"][:, None, :]
    MX, PX, QX = M @ X, P @ X, Q @ X
    R = np.abs(MX * co["cM"][:, None, :] + PX * co["t"][:, None, :] + QX * co["cQ"][:, None, :])
    AX = np.abs(X)
    AMX, APX, AQX = np.abs(M) @ AX, np.abs(P) @ AX, np.abs(Q) @ AX
    D = np.where(big, AMX + APX * a + AQX * a * a, AMX * a * a + APX * a + AQX)
    eta_c = np.max(ratio(R, D), axis=1, initial=0.0)
    num = np.einsum("bij,bij->bj", np.abs(Yc), D)
    den = np.abs(np.einsum("bij,bij->bj", Yc, MX * co["dM"][:, None, :]
                           + PX * co["dP"][:, None, :]))
    kappa_c = ratio(num, den)
    kappa_c = np.where(co["big"], kappa_c * np.abs(s), kappa_c)
    kappa_c = np.where(den > 0, kappa_c, np.inf)
    return eta_c, np.where((den == 0) & (num == 0), 0.0, kappa_c)


def _closure(link):
    """Labels (the smallest member) of the connected components of each (k, k) graph."""
    k = link.shape[-1]
    R = link | np.eye(k, dtype=bool)
    while True:
        Ri = R.astype(np.int32)
        R2 = (Ri @ Ri) > 0
        if np.array_equal(R2, R):
            break
        R = R2
    return np.argmax(R, axis=2)  # the first (smallest) index reachable: the label


def _clusters(sol, M, P, Q, cluster, sizes, cov, err, block, eta, holder2, scale, rank_tol):
    """The cluster rule of :func:`mbseig.modal.bounds.tolerances` for every cluster of two or
    more members of every covered problem at once, in place on err and block: the rank of the
    members' vectors (:func:`~mbseig.modal.bounds.numerical_ranks`, clusters of one size
    together), where it is short the nullity of T at the cluster's mean
    (:func:`~mbseig.modal.bounds.nullities`), the block count ⌈size / rank⌉, and the bound:
    the spread plus the first-order one (one block), or plus the Hölder radius of the blocks."""
    bb, cc = np.nonzero((sizes > 1) & cov[:, None])
    if not bb.size:
        return
    s = sol.eigenvalues
    label = cluster[bb]  # (G, k): the labels of each cluster's problem
    member = label == cc[:, None]  # (G, k): the members of each cluster
    size = sizes[bb, cc]
    for sz in np.unique(size):
        g_ = np.flatnonzero(size == sz)
        b = bb[g_]
        idx = np.nonzero(member[g_])[1].reshape(g_.size, sz)  # ascending, as flatnonzero
        sm = np.take_along_axis(s[b], idx, axis=1)
        mean = sm.sum(axis=1) / sz
        spread = np.max(np.abs(sm - mean[:, None]), axis=1)
        X = np.take_along_axis(sol.vectors[b], idx[:, None, :], axis=2)
        g = numerical_ranks(X, rank_tol)
        short = np.flatnonzero(g < sz)
        if short.size:
            bs = b[short]
            sc = np.maximum(np.abs(mean[short]), scale[bs])
            nul = nullities(M[bs], P[bs], Q[bs], mean[short], spread[short], sc)
            g[short] = np.minimum(np.maximum(g[short], nul), sz)
        nblock = np.maximum(1, -(-sz // np.maximum(g, 1)))
        e = np.take_along_axis(err[b], idx, axis=1)
        h = np.take_along_axis(holder2[b], idx, axis=1)
        first = np.max(np.where(np.isfinite(e), e, h), axis=1)
        Sc = np.maximum(np.abs(mean), scale[b])
        with np.errstate(over="ignore", invalid="ignore"):
            hol = Sc * np.max(np.take_along_axis(eta[b], idx, axis=1), axis=1) ** (
                1.0 / nblock)
        new = spread + np.where(nblock == 1, first, hol)
        rows = np.repeat(b, sz)
        err[rows, idx.ravel()] = np.repeat(new, sz)
        block[rows, idx.ravel()] = np.repeat(nblock, sz)


def batch_tolerances(sol, M, P, Q, *, safety=10.0, stability_rtol=1e-12, stability_atol=0.0,
                     rank_tol=1e-6) -> BatchBounds:
    """The bounds, tolerances and stabilities of the covered problems of ``sol`` (module
    docstring); M, P, Q (B, n, n) the problems it solved.  Rows of problems not covered are NaN
    (their stability codes CRITICAL): the caller takes those through the one-point stage.

    Parameters
    ----------
    sol : mbseig.eigen.batch.BatchSolution
        The pairs of the B problems.
    M, P, Q : ndarray, shape (B, n, n)
        The problems (P may be None).
    safety, stability_rtol, stability_atol, rank_tol : float
        As :func:`mbseig.modal.bounds.tolerances`.

    Returns
    -------
    BatchBounds
        Per problem and eigenvalue.
    """
    M = np.asarray(M, float)
    Q = np.asarray(Q, float)
    P = np.zeros_like(M) if P is None else np.asarray(P, float)
    s = sol.eigenvalues
    B, k = s.shape
    cov = sol.covered
    sv = np.where(cov[:, None], s, 0.0)
    eta = np.maximum(np.where(cov[:, None], sol.backward_error, 1.0), EPS)
    with np.errstate(over="ignore", invalid="ignore"):
        err = np.where(cov[:, None], sol.condition, 1.0) * eta
    err = np.where(np.isnan(err), np.inf, err)
    scale = _frequency_scale(sol.norms)[:, None]
    S = np.maximum(np.abs(sv), scale)
    holder2 = S * np.sqrt(eta)
    dist = np.abs(sv[:, :, None] - sv[:, None, :])
    far = dist.copy()
    far[:, np.arange(k), np.arange(k)] = np.inf
    near = far.min(axis=2) if k > 1 else np.full((B, k), np.inf)
    gaps = np.minimum.reduce([np.abs(sv), np.where(sv.real != 0, np.abs(sv.real), np.inf),
                              np.where(sv.imag != 0, np.abs(sv.imag), np.inf), near])
    undecided = (safety * err >= gaps) & cov[:, None]
    rows = np.flatnonzero(undecided.any(axis=1))
    if rows.size:
        eta_c, kappa_c = _componentwise(M[rows], P[rows], Q[rows], sv[rows],
                                        np.where(cov[rows, None, None], sol.vectors[rows], 0.0),
                                        np.where(cov[rows, None, None], sol.left[rows], 0.0))
        with np.errstate(over="ignore", invalid="ignore"):
            err_c = kappa_c * np.maximum(eta_c, EPS)
        err_c = np.where(np.isnan(err_c), np.inf, err_c)
        sub = err[rows]
        err[rows] = np.where(undecided[rows], np.minimum(sub, err_c), sub)
    # linking radius: first order, or the Hölder radius of the block it may belong to
    radius = np.where(np.isfinite(err), err, holder2)
    unit = np.max(np.abs(sv), axis=1, keepdims=True)
    unit = np.where(unit > 0, unit, 1.0)
    fin = np.isfinite(err) & (err > 0)
    if k > 1:
        first_reach = np.minimum(safety * err, 4.0 * unit)
        kk = np.full((B, k), 2)
        while True:
            with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
                reach = np.minimum(safety * S * eta ** (1.0 / kk), first_reach)
            counts = (dist <= reach[:, :, None]).sum(axis=2)
            grown = fin & (counts > kk)
            if not grown.any():
                break
            kk = np.where(grown, counts, kk)
        holder_k = S * eta ** (1.0 / np.maximum(counts, 1))
        radius = np.where(fin, np.where(counts > 1, np.minimum(err, holder_k), err), radius)
        reach = np.minimum(2 * safety * radius, 4.0 * unit)
        within = (dist <= reach[:, :, None]) | (dist <= reach[:, None, :])
        link = within & (dist <= safety * (radius[:, :, None] + radius[:, None, :]))
        link[:, np.arange(k), np.arange(k)] = False
        link &= cov[:, None, None]
        cluster = _closure(link) if link.any() else np.broadcast_to(np.arange(k), (B, k)).copy()
    else:
        cluster = np.zeros((B, k), int)
    block = np.ones((B, k), int)
    sizes = np.zeros((B, k), int)
    np.add.at(sizes, (np.repeat(np.arange(B), k), cluster.ravel()), 1)
    member_size = np.take_along_axis(sizes, cluster, axis=1)
    alone = (member_size == 1) & ~np.isfinite(err)
    err = np.where(alone, holder2, err)
    block = np.where(alone, 2, block)
    _clusters(sol, M, P, Q, cluster, sizes, cov, err, block, eta, holder2, scale[:, 0],
              rank_tol)
    tol = np.maximum.reduce([safety * err, stability_rtol * np.abs(sv),
                             np.full((B, k), stability_atol)])
    rigid = np.abs(sv) <= tol
    # the zero-pair floor (bounds.zero_pair_floor, γ = 1: the batch solves unscaled problems)
    cand = (np.abs(sv) <= 1e-3 * scale) & cov[:, None]
    if cand.any():
        rb = np.flatnonzero(cand.any(axis=1))
        X = sol.vectors[rb]
        mx = np.abs(np.einsum("bij,bij->bj", X.conj(), M[rb] @ X))
        px = np.abs(np.einsum("bij,bij->bj", X.conj(), P[rb] @ X))
        xx = np.einsum("bij,bij->bj", X.conj(), X).real
        nQ = sol.norms[rb, 2][:, None]
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            h = np.sqrt(eta[rb] * nQ * xx / np.where(mx > 0, mx, 1.0))
        apply = cand[rb] & (mx != 0) & (px <= np.abs(sv[rb]) * mx) & np.isfinite(h) \
            & (np.abs(sv[rb]) <= np.sqrt(safety) * h)
        err[rb] = np.where(apply, np.maximum(err[rb], h), err[rb])
        tol[rb] = np.where(apply, np.maximum(tol[rb], safety * h), tol[rb])
        rigid[rb] = rigid[rb] | apply
    delta = -sv.real
    stab = np.where(rigid, CRITICAL, np.where(delta > tol, STABLE,
                                              np.where(delta < -tol, UNSTABLE, CRITICAL)))
    nan = ~cov[:, None]
    err, tol = np.where(nan, np.nan, err), np.where(nan, np.nan, tol)
    return BatchBounds(err, tol, tol.copy(), rigid & cov[:, None],
                       np.where(nan, CRITICAL, stab), cluster, block)
