"""The measures of the pairs a partial search returns (:func:`mbseig.eigen.solve_partial`):
backward errors and condition numbers on the (bordered) pencil, verified against
``verify_tol``, vectors back in the coordinates of M, conjugate partners measured once, the
componentwise measures formed on demand.

Symmetric paths (eigh, proportional): each undamped mode v gives both roots of
s² + (α + βω²) s + ω² = 0 with x = v; with stiffness-proportional damping the multiplier rows
of a bordered vector scale as μ = (1 + βs) λ.  General paths: of each companion vector the
better half is kept (:func:`mbseig.eigen.measures.better_half`), and the left vectors are the
right ones for a symmetric pencil, else found by inverse iteration where asked.
"""

from __future__ import annotations

import numpy as np

from ..errors import SolverError
from .measures import (
    backward_errors,
    better_half,
    colnorm,
    componentwise,
    conditions,
    expand_pairs,
    is_symmetric,
    unit_columns,
)
from .selection import partner_columns
from .shift_invert import left_vectors
from .undamped import undamped_roots

__all__ = ["symmetric_pairs", "general_pairs", "Componentwise"]


def _verified(name, s, eta, verify_tol):
    bad = ~(eta <= verify_tol)
    if np.any(bad):
        worst = ", ".join(f"{z.real:.6g}{z.imag:+.6g}j (η={e:.1e})" for z, e in zip(s[bad][:5], eta[bad][:5]))
        raise SolverError(f"{name}: {int(bad.sum())} returned pairs fail the backward-error check "
                          f"η ≤ {verify_tol:g}: {worst}")


def symmetric_pairs(found, extras, pencil, norms, n, m, verify_tol, name):
    """(s, X, Y, η, κ, componentwise measures, 0) of the modes of a symmetric path."""
    Mb, Pb, Qb = pencil
    w, V = found["w"], found["V"]
    alpha, beta = extras.get("alpha", 0.0), extras.get("beta", 0.0)
    s = undamped_roots(w, alpha, beta)
    V = np.divide(V, colnorm(V), order="C")  # row-major: the measures run over blocks of rows
    X = np.concatenate([V, V], axis=1)
    if m and beta != 0.0:  # multipliers of the damped mode: μ = (1 + βs) λ (module doc)
        X = X.astype(complex)
        X[n:, :] *= (1.0 + beta * s)[None, :]
        X = unit_columns(X)
    eta, MX, PX = backward_errors((Mb, Pb, Qb), s, X, norms)
    Yc = X
    kappa = conditions(s, X, Yc, MX, PX, norms)
    _verified(name, s, eta, verify_tol)
    # the componentwise measures on demand (the listing asks for the few pairs the normwise
    # bound leaves undecided; at 10⁶ coordinates all of them cost ≈ 4 s)
    lazy = Componentwise((Mb, Pb, Qb), s, X, Yc, None, None)
    Xq = unit_columns(X[:n]) if m else X
    return s, Xq, Xq, eta, kappa, lazy, 0


def general_pairs(found, pencil, norms, n, m, verify_tol, name, sym_tol, left):
    """(s, X, Y, η, κ, componentwise measures, second halves kept) of every returned pair of a
    general path, the measures formed once per conjugate pair and copied to its partner."""
    Mb, Pb, Qb = pencil
    # a conjugate partner (s̄, x̄) of real M, P, Q has the η, κ, η_c, κ_c of (s, x): the
    # measures are formed on one column per pair (half the work) and copied to the partner
    s_all, X1, X2 = found["s"], found["X1"], found["X2"]
    src = partner_columns(s_all, X1)
    uniq = np.flatnonzero(src == np.arange(s_all.size))
    s = s_all[uniq]
    if uniq.size < s_all.size:
        X1, X2 = X1[:, uniq], (None if X2 is X1 else X2[:, uniq])
        X2 = X1 if X2 is None else X2
    del found["X1"], found["X2"]
    X, eta, MX, PX, n_second = better_half((Mb, Pb, Qb), s, X1, X2, norms)
    del X1, X2
    symmetric_all = all(is_symmetric(A, sym_tol) for A in (Mb, Pb, Qb))
    Yc = X if symmetric_all or not left else left_vectors(Mb, Pb, Qb, s)
    kappa = conditions(s, X, Yc, MX, PX, norms)
    del MX, PX
    pos = np.searchsorted(uniq, src)  # the measured column of each returned pair
    partner = src != np.arange(s_all.size)
    _verified(name, s, eta, verify_tol)
    lazy = Componentwise((Mb, Pb, Qb), s, X, Yc, pos, partner)
    Xq = unit_columns(X[:n]) if m else X
    Yq = Xq if Yc is X else (unit_columns(Yc[:n]) if m else Yc)
    del X, Yc
    # back to every returned pair: partners conjugated
    s, eta, kappa = s_all, eta[pos], kappa[pos]
    same = Yq is None or Yq is Xq  # y = x̄: the left vectors are the right ones, expanded once
    Xq = expand_pairs(Xq, pos, partner)
    Yq = Xq if same else expand_pairs(Yq, pos, partner)
    return s, Xq, Yq, eta, kappa, lazy, n_second


class Componentwise:
    """(η_c, κ_c) of returned pairs on demand (:meth:`QEPSolution.componentwise`), from the
    bordered pencil and the bordered vectors they were verified with; ``pos``/``partner`` map a
    returned pair to its measured column (a conjugate partner has the same measures).  A plain
    object (not a closure), so a solution stays picklable."""

    def __init__(self, pencil, s, X, Y, pos=None, partner=None):
        self.pencil, self.s, self.X, self.Y, self.pos, self.partner = pencil, s, X, Y, pos, partner

    def __call__(self, idx):
        cols = np.asarray(idx) if self.pos is None else np.unique(self.pos[np.asarray(idx)])
        Y = None if self.Y is None else self.Y[:, cols]
        eta_c, kappa_c = componentwise(self.pencil, self.s[cols], self.X[:, cols], Y)
        if self.pos is None:
            return eta_c, kappa_c
        where = np.searchsorted(cols, self.pos[np.asarray(idx)])
        return eta_c[where], kappa_c[where]
