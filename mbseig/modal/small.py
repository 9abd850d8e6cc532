"""The fused modes stage of small dense models: the solve of :mod:`mbseig.eigen.small`, the
error bounds and the listing in one pass, every shared quantity formed once (the distances
between the eigenvalues, the reversal, the weights).

:func:`small_modes` gives the :class:`~mbseig.modal.result.Modes` of the general stage
(:func:`mbseig.modal.modes`: :func:`~mbseig.modal.bounds.error_bounds`,
:func:`~mbseig.modal.bounds.zero_pair_floor`, :func:`~mbseig.modal.listing.listing`) with the
same numbers, or None where the general stage must run (see :mod:`mbseig.eigen.small`; also a
pair above ``eta_warn``, whose warning the general listing words).
"""

from __future__ import annotations

import math

import numpy as np

from ..eigen import EPS
from ..eigen.small import solve_small
from ..eigen.small_measures import componentwise_small
from .bounds import Bounds, components, frequency_scale, nullity, sharpen
from .small_listing import floor_zero_pairs, rank, small_listing

__all__ = ["small_modes"]


def small_modes(M, P, Q, *, N, coordinate_names, stability_rtol, stability_atol, safety,
                n_dominant, rigid_rank_tol, eta_warn, options):
    """The modes of a small dense problem by the fused path, or None (module docstring)."""
    sol = solve_small(M, P, Q, **options)
    if sol is None or (sol.backward_error > eta_warn).any():
        return None
    try:  # a floating-point exception (a bound beyond the double range): the general stage
        with np.errstate(over="raise", invalid="raise", divide="raise", under="ignore"):
            b = bounds(sol, safety, stability_rtol, stability_atol, rigid_rank_tol)
    except FloatingPointError:
        return None
    b = floor_zero_pairs(b, sol, M, P, safety)
    return small_listing(sol, b, N=N, coordinate_names=coordinate_names, n_dominant=n_dominant,
                         tolerances_used={"stability_rtol": stability_rtol,
                                    "stability_atol": stability_atol, "safety": safety,
                                    "rigid_rank_tol": rigid_rank_tol, "eta_warn": eta_warn})


def _holder_blocks(Df, S, eta, safety, first_reach):
    """bounds._holder_blocks on the precomputed distances Df of the points to all points."""
    k = np.full(Df.shape[0], 2)
    while True:
        reach = np.minimum(safety * S * eta ** (1.0 / k), first_reach)
        counts = (Df <= reach[:, None]).sum(axis=1)
        grown = counts > k
        if not grown.any():
            return counts
        k = np.where(grown, counts, k)


def bounds(sol, safety, stability_rtol, stability_atol, rank_tol):
    """:func:`mbseig.modal.bounds.error_bounds` for a small dense solution: the same rules and
    numbers, the pairwise distances of the eigenvalues formed once."""
    s = sol.eigenvalues
    k = s.size
    eta = np.maximum(sol.backward_error, EPS)
    err = sol.condition * eta
    err = np.where(np.isnan(err), np.inf, err)
    scale = frequency_scale(sol.norms)
    a_s = np.abs(s)
    S = np.maximum(a_s, scale)
    holder2 = S * np.sqrt(eta)
    if k > 1:
        unit = float(a_s.max()) or 1.0
        z = s.real / unit + 1j * (s.imag / unit)
        D = np.abs(z[:, None] - z[None, :])
        near = np.partition(D, 1, axis=1)[:, 1] * unit
    else:
        near = np.full(k, np.inf)
    gaps = np.minimum(np.minimum(a_s, np.where(s.real != 0, np.abs(s.real), np.inf)),
                      np.minimum(np.where(s.imag != 0, np.abs(s.imag), np.inf), near))
    idx = (safety * err >= gaps).nonzero()[0]
    if idx.size:
        sharpen(err, idx, *componentwise_small(sol, idx))
    radius = np.where(np.isfinite(err), err, holder2)
    cluster = np.arange(k)
    block = np.ones(k, int)
    if k > 1:
        finite = (np.isfinite(err) & (err > 0)).nonzero()[0]
        if finite.size:
            ef, Sf = err[finite], S[finite]
            counts = _holder_blocks(D[finite], Sf / unit, eta[finite], safety,
                                    np.minimum(safety * ef / unit, 4.0))
            holder_k = Sf * eta[finite] ** (1.0 / np.maximum(counts, 1))
            radius[finite] = np.where(counts > 1, np.minimum(ef, holder_k), ef)
        reach = np.minimum(2 * safety * radius / unit, 4.0)
        mask = D <= reach[:, None]
        pairs = set()
        if mask.sum() > k:
            ii, jj = np.nonzero(mask)
            ok = (jj != ii) & (np.abs(s[ii] - s[jj]) <= safety * (radius[ii] + radius[jj]))
            pairs = set(zip(np.minimum(ii, jj)[ok].tolist(), np.maximum(ii, jj)[ok].tolist(),
                            strict=True))
        cluster = components(k, pairs)
    sizes = np.bincount(cluster, minlength=k)
    alone = (sizes[cluster] == 1) & ~np.isfinite(err)
    err[alone], block[alone] = holder2[alone], 2
    geometric = np.ones(k, int)
    ranks = {}  # the rank of a block of vectors, once (a conjugate cluster of eigh: the same)
    for c in (sizes > 1).nonzero()[0].tolist():
        members = (cluster == c).nonzero()[0]
        sm = s[members]
        mean = sm.sum() / members.size
        spread = float(np.abs(sm - mean).max())
        Xm = sol.vectors[:, members]
        key = (Xm.dtype.char, Xm.shape, Xm.tobytes())
        g = ranks.get(key)
        if g is None:
            g = ranks[key] = rank(Xm, rank_tol)
        if g < members.size:
            g = min(max(g, nullity(sol, mean, spread, max(abs(mean), scale))), members.size)
        geometric[members] = g
        b = max(1, math.ceil(members.size / max(g, 1)))
        if b == 1:
            em = err[members]
            err[members] = spread + np.where(np.isfinite(em), em, holder2[members]).max()
        else:
            Sc = max(abs(mean), scale)
            err[members] = spread + Sc * float(eta[members].max()) ** (1.0 / b)
        block[members] = b
    tol = np.maximum(np.maximum(safety * err, stability_rtol * a_s), stability_atol)
    re_err = sol.real_error
    if re_err is None:
        tol_re = tol
    else:
        re_bound = np.where(block > 1, err, np.minimum(err, re_err))
        tol_re = np.maximum(np.maximum(safety * re_bound, stability_rtol * a_s), stability_atol)
    return Bounds(err, tol, tol_re, a_s <= tol, cluster, block, geometric)
