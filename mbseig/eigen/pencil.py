"""Regularity of the pencil M s² + P s + Q: a singular pencil (det ≡ 0) is refused before QZ with
a null vector for the caller to name the coordinates."""

from __future__ import annotations

import warnings

import numpy as np
import scipy.linalg as sla

from ..errors import SolverError
from .base import (
    SingularPencilError,
)
from .measures import (
    EPS,
    pow2_scale,
)


def _equilibrated(T):
    """(R T C, 1/C): T with rows, then columns, scaled to largest entry 1, and the column factors
    (a null vector v of R T C is C v for T); None when T has a zero row or column."""
    r = np.max(np.abs(T), axis=1)
    if np.any(r == 0):
        return None
    T = pow2_scale(T, -np.frexp(r)[1][:, None])  # powers of two: exact, never overflowing
    c = np.max(np.abs(T), axis=0)
    if np.any(c == 0):
        return None
    ec = np.frexp(c)[1]
    return pow2_scale(T, -ec[None, :]), np.ldexp(1.0, ec)


def _null_vector(T):
    """A unit null vector of a (numerically) singular T: a zero column or row if there is one,
    else the last right singular vector of the equilibrated T mapped back."""
    for axis in (0, 1):
        zero = np.flatnonzero(np.max(np.abs(T), axis=axis) == 0)
        if zero.size:
            v = np.zeros(T.shape[0], complex)
            v[zero[0]] = 1.0
            return v, 0.0
    Te, c = _equilibrated(T)
    _, sv, Vh = np.linalg.svd(Te)
    v = Vh[-1].conj() / c
    return v / np.linalg.norm(v), float(sv[-1])


def check_regular(M, P, Q, norms, *, tol=None, seed=20240):
    """Raise :class:`SingularPencilError` when det(M s² + P s + Q) vanishes identically.

    T(z) = z²M + zP + Q, rows and columns equilibrated (so that a regular pencil whose
    eigenvalues span many orders is not mistaken for a singular one), is factorized (LU) at two
    random points z of modulus ~ γ = √(‖Q‖/‖M‖); a regular pencil is nonsingular at both (they
    are no eigenvalue, with probability one).  σ_min is estimated by three steps of inverse
    iteration on TᴴT; the pencil counts as singular when it is ≤ ``tol`` (default 100 n ε) at
    both points, or when T has a zero row or column.  The null vector of T at the last point
    (SVD, only then) is attached for naming.
    """
    n = M.shape[0]
    tol = 100 * n * EPS if tol is None else tol
    nM, _, nQ = norms
    gamma = np.sqrt(nQ / nM) if nM > 0 and nQ > 0 else 1.0
    rng = np.random.default_rng(seed)
    T = None
    for _ in range(2):
        z = gamma * rng.uniform(0.5, 2.0) * np.exp(1j * rng.uniform(0.1, np.pi - 0.1))
        with np.errstate(over="ignore", invalid="ignore"):
            T = (z * z) * M + z * P + Q
        if not np.all(np.isfinite(T)):
            raise SolverError("M s² + P s + Q overflows at |s| ~ √(‖Q‖/‖M‖): the model's entries "
                              "span more than double precision resolves; rescale the units")
        eq = _equilibrated(T)
        if eq is None:
            continue
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", sla.LinAlgWarning)  # an exact zero pivot: singular
            lu = sla.lu_factor(eq[0], check_finite=False)
        if np.any(np.diagonal(lu[0]) == 0):
            continue
        b = rng.standard_normal(n) + 1j * rng.standard_normal(n)
        sigma = 0.0
        with np.errstate(over="ignore", invalid="ignore"):  # overflow: σ_min = 0 to precision
            for _ in range(3):
                x = sla.lu_solve(lu, b / np.linalg.norm(b), check_finite=False)
                y = sla.lu_solve(lu, x / np.linalg.norm(x), trans=2, check_finite=False)
                if not (np.all(np.isfinite(x)) and np.all(np.isfinite(y))):
                    sigma = 0.0
                    break
                sigma = 1.0 / np.sqrt(np.linalg.norm(x) * np.linalg.norm(y))
                b = y
        if sigma > tol:
            return
    v, smin = _null_vector(T)
    raise SingularPencilError(
        f"singular pencil: det(M s² + P s + Q) ≡ 0 (equilibrated σ_min = {smin:.1e} at two "
        f"random s): a coordinate or combination without mass, damping or stiffness; every s "
        f"would be an eigenvalue", vector=v)
