"""The measures of the pairs a partial search returns (:func:`mbseig.eigen.solve_partial`):
backward errors and condition numbers on the (bordered) pencil, verified against
``verify_tol``, vectors back in the coordinates of M, conjugate partners measured once, the
componentwise measures formed on demand.

Symmetric paths (eigh, proportional): each undamped mode v gives both roots of
s² + (α + βω²) s + ω² = 0 with x = v; with stiffness-proportional damping the multiplier rows
of a bordered vector scale as μ = (1 + βs) λ.  The roots of an oscillating mode are exact
conjugates and so are their vectors, so each such mode is measured once.  General paths: of
each companion vector the better half is kept (:func:`mbseig.eigen.measures.better_half`), and
the left vectors are the right ones for a symmetric pencil, else found by inverse iteration
where asked; a search that knows its partners (partial-slepc) passes the measured columns and
the partner map, else the partners are found in the expanded vectors.  The measures of a
partner are bitwise those of its pair (every quantity is the conjugate or the same modulus).
"""

from __future__ import annotations

import numpy as np

from ..errors import SolverError
from .measures import (
    better_half_norms,
    colnorm,
    componentwise,
    conditions,
    eta_kappa,
    expand_pairs,
    is_symmetric,
    plain_norms,
    unit_columns,
)
from .selection import partner_columns
from .shift_invert import left_vectors
from .undamped import undamped_roots

__all__ = ["Componentwise", "general_pairs", "symmetric_pairs", "take_columns"]


def take_columns(X, cols):
    """X[:, cols] in row-major order (the measures run over blocks of rows), X itself where
    ``cols`` is every column in order and X is row-major already."""
    cols = np.asarray(cols)
    if (X.flags.c_contiguous and cols.size == X.shape[1]
            and np.array_equal(cols, np.arange(cols.size))):
        return X
    return expand_pairs(X, cols, np.zeros(cols.size, bool))


def _verified(name, s, eta, verify_tol):
    bad = ~(eta <= verify_tol)
    if np.any(bad):
        worst = ", ".join(f"{z.real:.6g}{z.imag:+.6g}j (η={e:.1e})"
                          for z, e in zip(s[bad][:5], eta[bad][:5], strict=True))
        raise SolverError(f"{name}: {int(bad.sum())} returned pairs fail the backward-error check "
                          f"η ≤ {verify_tol:g}: {worst}")


def symmetric_pairs(found, extras, pencil, norms, n, m, verify_tol, name):
    """(s, X, Y, η, κ, componentwise measures, 0) of the modes of a symmetric path."""
    Mb, Pb, Qb = pencil
    w, V = found["w"], found["V"]
    alpha, beta = extras.get("alpha", 0.0), extras.get("beta", 0.0)
    s_all = undamped_roots(w, alpha, beta)  # [s₊; s₋], s₋ = s̄₊ exactly for an oscillating mode
    k = w.size
    V = np.divide(V, colnorm(V), order="C")  # row-major: the measures run over blocks of rows
    # the returned pairs are (s₊, v) then (s₋, v); the multipliers scaled by (1 + βs) are
    # conjugate with s, so (s̄₊, x̄₊) is the partner of (s₊, x₊) and is measured once (module doc)
    partner = np.zeros(2 * k, bool)
    partner[k:] = s_all[k:] == np.conj(s_all[:k])
    partner[k:] &= s_all[:k].imag != 0
    pos = np.cumsum(~partner) - 1
    pos[k:][partner[k:]] = pos[:k][partner[k:]]
    meas = np.flatnonzero(~partner)  # the returned pair of each measured column
    vcol = meas % k
    s = s_all[meas]
    X = V if vcol.size == k else take_columns(V, vcol)
    if m and beta != 0.0:  # multipliers of the damped mode: μ = (1 + βs) λ (module doc)
        X = X.astype(complex)
        X[n:, :] *= (1.0 + beta * s)[None, :]
        X = unit_columns(X, inplace=True)
    eta, kappa, _ = eta_kappa((Mb, Pb, Qb), s, X, X, norms)
    _verified(name, s, eta, verify_tol)
    # the componentwise measures on demand (the listing asks for the few pairs the normwise
    # bound leaves undecided; at 10⁶ coordinates all of them cost ≈ 4 s)
    lazy = Componentwise((Mb, Pb, Qb), s, X, None, pos, partner)
    Xq = _returned(X, n, m, pos, partner)
    return s_all, Xq, Xq, eta[pos], kappa[pos], lazy, 0


def _returned(X, n, m, pos, partner):
    """The returned vectors: the measured columns in the coordinates of M (unit columns),
    one per returned pair, conjugated for the partners."""
    Xn = X[:n] if m else X
    nrm = plain_norms(Xn) if m else None
    if m and nrm is None:
        Xn = unit_columns(Xn)
    return expand_pairs(Xn, pos, partner, divide=nrm)


def general_pairs(found, pencil, norms, n, m, verify_tol, name, sym_tol, left):
    """(s, X, Y, η, κ, componentwise measures, second halves kept) of every returned pair of a
    general path, the measures formed once per conjugate pair and copied to its partner."""
    Mb, Pb, Qb = pencil
    # a conjugate partner (s̄, x̄) of real M, P, Q has the η, κ, η_c, κ_c of (s, x): the
    # measures are formed on one column per pair (half the work) and copied to the partner
    s_all = found["s"]
    if "partner" in found:  # the search's measured columns (row-major) and its partner map
        partner = found.pop("partner")
        X1 = X2 = found.pop("X")
        pos = np.cumsum(~partner) - 1
        uniq = np.flatnonzero(~partner)
    else:
        X1, X2 = found.pop("X1"), found.pop("X2")
        src = partner_columns(s_all, X1)
        uniq = np.flatnonzero(src == np.arange(s_all.size))
        if uniq.size < s_all.size:
            X1, X2 = take_columns(X1, uniq), (None if X2 is X1 else take_columns(X2, uniq))
            X2 = X1 if X2 is None else X2
        pos = np.searchsorted(uniq, src)  # the measured column of each returned pair
        partner = src != np.arange(s_all.size)
    s = s_all[uniq]
    symmetric_all = all(is_symmetric(A, sym_tol) for A in (Mb, Pb, Qb))
    Yc = None if symmetric_all or not left else left_vectors(Mb, Pb, Qb, s)
    if X2 is X1:  # one vector per pair: η and κ in one pass (no whole M X, P X)
        X, n_second = unit_columns(X1, inplace=True), 0
        X = np.ascontiguousarray(X)
        Yc = X if Yc is None else Yc
        eta, kappa, _ = eta_kappa((Mb, Pb, Qb), s, X, Yc, norms)
    else:  # two halves: the better one per column first, then κ from its products
        X, eta, MX, PX, n_second, xn = better_half_norms((Mb, Pb, Qb), s, X1, X2, norms, own=True)
        Yc = X if Yc is None else Yc
        kappa = conditions(s, X, Yc, MX, PX, norms, xn=xn)
        del MX, PX
    del X1, X2
    _verified(name, s, eta, verify_tol)
    lazy = Componentwise((Mb, Pb, Qb), s, X, None if Yc is X else Yc, pos, partner)
    # back to every returned pair: partners conjugated; y = x̄: the left vectors are the right
    # ones, expanded once
    Xq = _returned(X, n, m, pos, partner)
    Yq = Xq if Yc is X else _returned(Yc, n, m, pos, partner)
    return s_all, Xq, Yq, eta[pos], kappa[pos], lazy, n_second


class Componentwise:
    """(η_c, κ_c) of returned pairs on demand (:meth:`QEPSolution.componentwise`), from the
    bordered pencil and the bordered vectors they were verified with; ``pos``/``partner`` map a
    returned pair to its measured column (a conjugate partner has the same measures).  A plain
    object (not a closure), so a solution stays picklable."""

    def __init__(self, pencil, s, X, Y, pos=None, partner=None):
        self.pencil, self.s, self.X, self.Y, self.pos, self.partner = pencil, s, X, Y, pos, partner
        self.abs_ops = None

    def __call__(self, idx):
        idx = np.asarray(idx)
        cols = idx if self.pos is None else np.unique(self.pos[idx])
        X = take_columns(self.X, cols)
        Y = None if self.Y is None else take_columns(self.Y, cols)
        if self.abs_ops is None:  # |M|, |P|, |Q| once per solution
            self.abs_ops = tuple(abs(A) for A in self.pencil)
        eta_c, kappa_c = componentwise(self.pencil, self.s[cols], X, Y, abs_ops=self.abs_ops)
        if self.pos is None:
            return eta_c, kappa_c
        where = np.searchsorted(cols, self.pos[idx])
        return eta_c[where], kappa_c[where]
