"""Linear algebra of the statics: the Newton matrix, minimum-norm corrections, multipliers and
the size of a step in the model's own scales (docs/design.md, "Equilibrium").

Sizes.  A coordinate is measured in its own scale ℓ_i: the model's length scale L for length
coordinates (``coordinate_kinds``, recorded by the reader: :mod:`mbseig.model.assembly`), 1 for
angles, unit-vector components and modal amplitudes.  A
rigid length (a distance constraint between the ends of a body or a rod) is measured by the
rotation it makes, |Δd|/L_body.  The size of a step is the largest of these
(:class:`StepScales`); the trust region and the convergence test use it.

Newton matrix.  The augmented matrix [[K + H, Φ_qᵀ], [Φ_q, 0]] is equilibrated (symmetric
diagonal scaling by the square roots of its largest row entries, so that stiff and soft members
and the constraint rows meet at one scale) and

- up to ``SMALL`` unknowns decomposed by the SVD: minimum-norm solutions, and the part of the
  right-hand side outside its range (the forces its stiffness cannot balance) is returned;
- above, factorized by sparse LU; a singular factor falls back to the SVD up to
  ``DENSE_LIMIT`` unknowns, and is an error beyond.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from ..errors import EquilibriumError
from ..model.elements import DistanceConstraint
from ..model.cache import KeptValues
from ..numerics import (
    LazyModule,
    blas_limit,
    constraint_rank,
    coo_sum,
    dense,
    equilibration,
    rank_of,
    saddle,
)

spla = LazyModule("scipy.sparse.linalg")  # sparse solvers: imported at first use

__all__ = ["SMALL", "DENSE_LIMIT", "StepScales", "NewtonMatrix", "multipliers",
           "augmented", "blas_threads", "solve_bordered"]

SMALL = 300  # augmented size up to which the Newton matrix is decomposed by the SVD
DENSE_LIMIT = 4000  # size up to which a singular sparse factor falls back to the dense SVD
RCOND = 1e-14  # singular values below RCOND·σ_max of the equilibrated matrix count as zero
LU_RCOND = 1e-8  # a small Newton matrix of the statics' Newton is solved by LU above this rcond


def blas_threads(n):
    """A context capping BLAS at ``n`` threads while it is open (threadpoolctl, when installed;
    nothing when n is None).  The statics factorizes many small and middle-sized dense matrices,
    for which a second BLAS thread only adds synchronization, and on a busy machine far more:
    a 200×200 solve measured 0.33 s with two OpenBLAS threads on a loaded 2-core machine.
    (:func:`mbseig.numerics.blas_limit`: one controller per process.)"""
    return blas_limit(n)


# StepScales.of: the last few scales by their model's elements (each kept with the elements it
# was made from, so that their ids, in the key, cannot be taken by other objects meanwhile)
_SCALES = KeptValues(8)


class StepScales:
    """ℓ_i per coordinate and the rigid lengths' direction maps (module docstring)."""

    def __init__(self, model):
        L = float(getattr(model, "length_scale", 1.0) or 1.0)
        self.length = L
        # a position component scales with the model's length; directions, angles and modal
        # amplitudes are dimensionless (mbseig.model.assembly)
        self.ell = np.array([L if kind == "length" else 1.0 for kind in model.coordinate_kinds])
        rows, cols, vals, inv_len = [], [], [], []
        r = 0
        for c in model.constraints:
            if isinstance(c, DistanceConstraint) and c.length > 0 and c.idx.size:
                C = c.diff.C
                rr, cc = np.nonzero(C)
                rows.append(rr + r)
                cols.append(c.idx[cc])
                vals.append(C[rr, cc])
                inv_len += [1.0 / c.length] * C.shape[0]
                r += C.shape[0]
        self.dims = model.dimension
        if r:
            self.D = coo_sum(r, model.n, [(np.concatenate(rows), np.concatenate(cols),
                                           np.concatenate(vals))])
            self.inv_len = np.array(inv_len)
        else:
            self.D = None

    @classmethod
    def of(cls, model):
        """The scales of ``model``, made once for the models that share its constraint elements,
        coordinate kinds, length scale and dimension (everything :class:`StepScales` reads): a
        solve builds several models of one device (inverse statics, the points of a sweep)."""
        constraints = tuple(model.constraints)
        key = (tuple(map(id, constraints)), float(getattr(model, "length_scale", 1.0) or 1.0),
               tuple(model.coordinate_kinds), getattr(model, "dimension", None))
        return _SCALES.get(key, lambda: (constraints, cls(model)))[1]

    def weights(self, n_total):
        """The metric 1/ℓ² of the coordinates (0 for the multipliers) of an augmented vector."""
        w = np.zeros(n_total)
        w[:self.ell.size] = 1.0 / self.ell**2
        return w

    def size(self, dq) -> float:
        """max(|Δq_i|/ℓ_i, |Δd_b|/L_b): the step in lengths of the model and radians."""
        s = float(np.max(np.abs(dq) / self.ell, initial=0.0))
        if self.D is not None:
            dd = (self.D @ dq) * self.inv_len
            k = self.dims
            rot = (np.sqrt(np.add.reduceat(dd * dd, np.arange(0, dd.size, k))) if k > 1
                   else np.abs(dd))
            s = max(s, float(np.max(rot, initial=0.0)))
        return s

    def largest(self, dq, names, count=3):
        """The ``count`` coordinates with the largest |Δq_i|/ℓ_i, as (name, Δq_i)."""
        rel = np.abs(dq) / self.ell
        order = np.argsort(-rel, kind="stable")[:count]
        return [(names[i], float(dq[i])) for i in order if rel[i] > 0]


def augmented(model, q, lam):
    """[[K + H(λ), Φ_qᵀ], [Φ_q, 0]] (CSR, or a dense array when the model's evaluations are
    dense: :class:`mbseig.statics.cache.Memo` of a small model) and Φ_q at q."""
    K, _ = model.force_jacobians(q)
    Phi_q = model.phi_q(q)
    if model.n_constraints:
        H = model.constraint_hessian(q, lam)
        A = saddle(K + H, Phi_q)
    else:
        A = K.tocsr() if sp.issparse(K) else K
    return A, Phi_q


class NewtonMatrix:
    """A factorized Newton matrix: ``solve(b)`` returns (x, e) with x the (minimum-norm)
    solution of A x = b and e = b − A x (zero for an LU factor: A is then nonsingular)."""

    def __init__(self, A, *, what="Newton matrix", weights=None, lu_first=False):
        self.weights = weights  # metric of the unknowns in which solutions are made least
        self.dense_lu = None
        N = A.shape[0]
        if N > SMALL or sp.issparse(A):  # (a small dense A stays dense: decomposed by the SVD)
            A = A if isinstance(A, sp.csr_matrix) else sp.csr_matrix(A)
        self.A = A
        self.d = equilibration(self.A)
        self.kind = "svd"
        self.lu = None
        if N > SMALL:
            # (D A D made CSC at once: the CSR product let go before SuperLU copies and factors
            # it, a copy of the whole Newton matrix less at the peak)
            As = (sp.diags(self.d) @ self.A @ sp.diags(self.d)).tocsc()
            with np.errstate(all="ignore"):
                try:
                    self.lu = spla.splu(As)
                    self.kind = "lu"
                except RuntimeError:
                    self.lu = None
            if self.lu is None and N > DENSE_LIMIT:
                raise EquilibriumError(
                    f"singular {what} of size {N} (redundant constraints or a free motion in a "
                    f"model above the dense limit of {DENSE_LIMIT})", element="equilibrium")
        if self.lu is None and lu_first and N <= SMALL and self._dense_lu(N):
            return
        if self.lu is None:
            with np.errstate(all="ignore"):
                As = self.d[:, None] * dense(self.A) * self.d[None, :]
                U, s, Vt = sla.svd(As, full_matrices=False, lapack_driver="gesdd")
            keep = s > RCOND * (s[0] if s.size else 0.0)
            self.U, self.s, self.Vt, self.keep = U[:, keep], s[keep], Vt[keep], keep
            self.null = self.d[:, None] * Vt[~keep].T  # null A = D · null(DAD)
            self.cond = float(s[0] / s[keep][-1]) if keep.any() else np.inf
            self.rank = int(keep.sum())
        else:  # (no condition estimate: forming U from SuperLU costs more than the solve)
            self.rank = N
            self.cond = float("nan")

    def _dense_lu(self, N) -> bool:
        """A small matrix factorized by dense LU (``lu_first``) where it is well conditioned:
        LAPACK's estimate of the 1-norm rcond of the equilibrated matrix above ``LU_RCOND``.
        The SVD's rank rule (σ_min > ``RCOND``·σ_max) then holds with a margin of 10⁶/N, the
        matrix is nonsingular, and both give its one solution to cond·ε (the SVD costs 5–8
        times the LU on the small matrices of a model of a few dozen coordinates).  False
        leaves the matrix to the SVD."""
        with np.errstate(all="ignore"):
            As = self.d[:, None] * dense(self.A) * self.d[None, :]
            if not np.all(np.isfinite(As)):
                return False
            lu, piv, info = sla.lapack.dgetrf(As)
            if info != 0:
                return False
            anorm = float(np.max(np.sum(np.abs(As), axis=0), initial=0.0))
            rcond, info = sla.lapack.dgecon(lu, anorm, norm="1")
        if info != 0 or not rcond > LU_RCOND:
            return False
        self.dense_lu = (lu, piv)
        self.kind, self.rank = "lu", N
        self.cond = float("nan")  # (no condition number: as for the sparse LU)
        self.null = np.zeros((N, 0))
        return True

    def motion(self, b):
        """The motion without restoring force along which the force b pushes: the projection
        of b onto null A (zero when A is nonsingular, or factorized by LU)."""
        if self.lu is not None or not self.null.shape[1]:
            return np.zeros_like(b)
        Z = self.null
        return Z @ np.linalg.lstsq(Z, b, rcond=None)[0]

    def solve(self, b):
        bs = self.d * b
        if self.dense_lu is not None:
            with np.errstate(all="ignore"):
                y, info = sla.lapack.dgetrs(*self.dense_lu, bs)
            if info != 0 or not np.all(np.isfinite(y)):
                raise EquilibriumError("the Newton matrix is numerically singular (dense LU)",
                                       element="equilibrium")
            return self.d * y, np.zeros_like(b)
        if self.lu is not None:
            with np.errstate(all="ignore"):
                y = self.lu.solve(bs)
            if not np.all(np.isfinite(y)):
                raise EquilibriumError("the Newton matrix is numerically singular (sparse LU)",
                                       element="equilibrium")
            x = self.d * y
            return x, np.zeros_like(b)
        c = self.U.T @ bs
        y = self.Vt.T @ (c / self.s)
        es = bs - self.U @ c  # the part of the (scaled) right-hand side outside the range
        x = self.d * y
        if self.weights is not None and self.null.shape[1]:
            # the solution least in the given metric: no motion along null A in it
            w = np.sqrt(self.weights)
            Zw = self.null * w[:, None]
            if np.any(Zw):
                x = x - self.null @ np.linalg.lstsq(Zw, w * x, rcond=None)[0]
        return x, es / self.d


def solve_bordered(A, col, row, corner, f, g, weights=None):
    """(x, τ) solving [[A, col], [rowᵀ, corner]] [x; τ] = [f; g] (a pseudo-arclength corrector's
    matrix).  Above ``SMALL`` unknowns by block elimination on one sparse LU of A — the dense
    border would fill a factorization of the whole matrix — accepted when the bordered residual
    is below 1e-10 of its terms; otherwise (A singular at a fold, or small) by
    :class:`NewtonMatrix` on the whole bordered matrix."""
    N = A.shape[0]
    if N > SMALL:
        try:
            NM = NewtonMatrix(A)
        except EquilibriumError:
            NM = None
        if NM is not None and NM.lu is not None:
            a, _ = NM.solve(f)
            b, _ = NM.solve(col)
            den = corner - float(row @ b)
            if den and np.isfinite(den):
                tau = (g - float(row @ a)) / den
                x = a - tau * b
                with np.errstate(all="ignore"):
                    r1 = A @ x + col * tau - f
                    r2 = float(row @ x) + corner * tau - g
                    scale = (abs(A) @ np.abs(x) + np.abs(col) * abs(tau) + np.abs(f))
                    ok = (np.all(np.abs(r1) <= 1e-10 * scale + 1e-300)
                          and abs(r2) <= 1e-10 * (float(np.abs(row) @ np.abs(x))
                                                  + abs(corner * tau) + abs(g)) + 1e-300)
                if ok and np.all(np.isfinite(x)):
                    return x, tau
    if N <= SMALL:
        B = np.block([[dense(A), col[:, None]], [row[None, :], np.array([[corner]])]])
    else:
        B = sp.bmat([[sp.csr_matrix(A), sp.csr_matrix(col[:, None])],
                     [sp.csr_matrix(row[None, :]), sp.csr_matrix([[corner]])]], format="csr")
    z = NewtonMatrix(B, weights=weights).solve(np.concatenate([f, [g]]))[0]
    return z[:N], float(z[N])


def multipliers(Phi_q, g, rank_tol, *, check, rank=None):
    """(λ, rank of Φ_q, how the rank was found) with λ the least-squares solution of Φ_qᵀλ = g.

    Small models (up to ``SMALL`` unknowns), and any model up to ``DENSE_LIMIT`` whose
    constraints are dependent: the SVD, so λ is the minimum-norm solution and the rank is
    revealed by the singular values (``check``).  Otherwise the normal equations
    Φ_q Φ_qᵀ λ = Φ_q g by sparse LU; that needs independent constraints, so a pivot below
    rank_tol² of the largest (the square: Φ_qΦ_qᵀ squares the singular values) means dependent
    constraints: the SVD up to ``DENSE_LIMIT``, an error beyond (instead of a guess).  ``rank``:
    the rank already found by a decomposition of Φ_q (the local basis of a model with frames,
    :mod:`mbseig.model.tangent`); where it is m and the pivots agree, no SVD is made for it.
    """
    m, n = Phi_q.shape
    if m == 0:
        return np.zeros(0), 0, "none"
    if m + n > SMALL:
        A = sp.csc_matrix(Phi_q @ Phi_q.T)
        with np.errstate(all="ignore"):
            try:
                lu = spla.splu(A)
            except RuntimeError:
                lu = None
        pivots = np.abs(lu.U.diagonal()) if lu is not None else np.zeros(1)
        if lu is not None and pivots.min() > rank_tol**2 * pivots.max():
            lam = lu.solve(Phi_q @ g)
            if m + n > DENSE_LIMIT or not check:
                return lam, m, ("sparse LU of Φ_q Φ_qᵀ (independent constraints verified by its "
                                "pivots)")
            if rank == m:
                return lam, m, ("sparse LU of Φ_q Φ_qᵀ (independent constraints: the local "
                                "basis's rank and the LU's pivots)")
            return lam, constraint_rank(Phi_q, rank_tol)[0], "SVD of Φ_q"
        if m + n > DENSE_LIMIT:
            raise EquilibriumError(
                f"redundant constraints in a model of {n} coordinates and {m} constraints: above "
                f"the dense limit of {DENSE_LIMIT} the constraints must be independent",
                element="equilibrium")
    with np.errstate(all="ignore"):
        lam, _, _, sv = sla.lstsq(dense(Phi_q).T, g, lapack_driver="gelsd")
    # the rank from the same SVD (gelsd's singular values of Φ_qᵀ are Φ_q's), as
    # constraint_rank decides it
    rank = rank_of(sv, rank_tol) if check else m
    return lam, rank, "SVD of Φ_q"
