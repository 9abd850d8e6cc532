"""Shift-invert machinery of the partial paths (:mod:`mbseig.eigen.partial`): the problem a search
runs on, the LU of the shifted pencil, the bordered pencil of constrained models, ARPACK runs
(Lanczos on the undamped problem, Arnoldi on the companion pencil) and left vectors by inverse
iteration."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from ..errors import SolverError
from ..numerics import LazyModule, equilibration
from .measures import (
    EPS,
    fro,
)

spla = LazyModule("scipy.sparse.linalg")  # sparse solvers: imported at first use


SHIFT_OFFSETS = (0.0, 1e-6, 1e-4, 1e-2)  # relative moves of a shift that sits on an eigenvalue


# A shift is kept unless σ²M + σP + Q is singular to working precision there (a shift on an
# eigenvalue): exactly singular, or cond > 1/(10 ε) (``SHIFT_KEEP``), the condition of the matrix
# with its rows and columns scaled alike to unit largest entries (:func:`_scaled_condition`: the
# units of the coordinates do not decide, rotations in milliradians moved the shift of a
# cantilever 5e7 times its lowest eigenvalue below it).  The LU is backward stable
# below that, and shift-invert at σ converges to the eigenvalues nearest σ however
# ill-conditioned the matrix is in norm: a fine FE mesh has cond(Q) ≈ 1e12 at σ = 0 with no
# eigenvalue near 0 (short elements' axial and bending stiffness against the lowest mode; it
# grows as the square of the element count), and moving σ by 1e-6 ‖Q‖/‖M‖ put it 1e5 lowest
# eigenvalues below the spectrum (Lanczos: 9,000 solves instead of 45 on 18,000 beam DOF).
# Once moved, the ladder goes on until the moved shift is well conditioned (``SHIFT_COND``):
# a free-free chain's Jordan block at 0 needs that for backward errors of 1e-12.  The limit of
# a normwise test: cond(Q) of a clamped Euler-Bernoulli beam grows as the fourth power of the
# element count (4.5e14 at 1500 elements a beam), and a free-free beam's rigid-body zeros are
# not exactly singular in floating point either; past that mesh the two look alike in norm,
# and keeping every non-singular shift gave a free-free bar spurious eigenvalues near 0.
SHIFT_KEEP = 1.0 / (10 * EPS)
SHIFT_COND = 1.0 / (1e4 * EPS)  # a moved shift: the ladder goes on until it is this well off


@dataclass(frozen=True, eq=False)
class Search:
    """The problem a partial search runs on: the (bordered) pencil Mb, Pb, Qb, the unbordered
    M, P, Q, ARPACK's options, the frequency scale ``w_scale``, the degrees of freedom and the
    largest count a search may ask (``limit``)."""

    Mb: object
    Pb: object
    Qb: object
    M: object
    P: object
    Q: object
    ncv: int | None
    maxiter: int | None
    tol: float
    purify: bool
    w_scale: float
    dof: int
    limit: int
    sym_tol: float
    norms: tuple


def _scaled_condition(A, lu, b):
    """cond(D A D) from below, D = diag(1/√max_j |A_ij|) (rows and columns scaled alike): the
    normwise estimate ‖S‖_F ‖S⁻¹b‖/‖b‖ of the symmetrically scaled matrix S, from one solve with
    A's LU (S⁻¹ b = D⁻¹ A⁻¹ D⁻¹ b).  The units of the coordinates do not enter (a model with its
    rotations in milliradians has ‖A‖ ‖A⁻¹‖ 10⁶× its own in radians), the singularity of A at
    an eigenvalue does."""
    A = sp.csr_matrix(A)
    d = equilibration(A)  # (the statics' Newton matrix is scaled so too)
    rows = np.repeat(np.arange(A.shape[0]), np.diff(A.indptr))
    with np.errstate(over="ignore", invalid="ignore"):
        y = lu.solve((b / d).astype(lu.U.dtype)) / d  # one solve: ‖S⁻¹‖ from below
        norm_s = float(np.linalg.norm(A.data * d[rows] * d[A.indices]))
        cond = norm_s * float(np.linalg.norm(y)) / float(np.linalg.norm(b))
    return cond if np.isfinite(cond) else np.inf


class ShiftLU:
    """LU of σ²M + σP + Q (``quadratic``) or Q − σM, at σ or, when that is (nearly) singular,
    at σ moved left by ``SHIFT_OFFSETS`` × ``scale`` (module docstring)."""

    def __init__(self, M, P, Q, sigma, scale, quadratic=True):
        best, last = None, None
        b = np.random.default_rng(7).standard_normal(M.shape[0])
        for off in SHIFT_OFFSETS:
            sig = sigma - off * scale
            A = (sig * sig * M + sig * P + Q) if quadratic else (Q - sig * M)
            try:
                lu = spla.splu(A.tocsc())
            except RuntimeError as exc:  # exactly singular: σ is an eigenvalue
                last = exc
                continue
            cond = _scaled_condition(A, lu, b)
            if best is None or cond < best[2]:
                best = (lu, sig, cond)
            if cond <= (SHIFT_KEEP if off == 0.0 else SHIFT_COND):
                break
        if best is None:
            raise SolverError(f"shift-invert: σ²M + σP + Q is singular at σ = {sigma:.6g} and "
                              f"every nearby shift tried ({last}): a coordinate without mass, "
                              f"damping or stiffness?")
        self.lu, self.sigma, self.cond = best
        self.n_solves = 0  # right-hand sides solved (real columns), for the path's details

    def solve(self, b, trans="N"):
        b = np.asarray(b)
        self.n_solves += (1 if b.ndim == 1 else b.shape[1]) * (2 if np.iscomplexobj(b) else 1)
        if np.iscomplexobj(b) and not np.iscomplexobj(self.lu.U.data):  # real factors
            return self.lu.solve(np.ascontiguousarray(b.real), trans=trans) \
                + 1j * self.lu.solve(np.ascontiguousarray(b.imag), trans=trans)
        return self.lu.solve(b, trans=trans)


def bordered(M, P, Q, G):
    m = G.shape[0]
    nQ, nG = fro(Q), fro(G)
    c = nQ / nG if nG > 0 and nQ > 0 else 1.0
    Z = sp.csr_matrix((m, m))
    Mb = sp.block_diag([M, Z], format="csr")
    Pb = sp.block_diag([P, Z], format="csr")
    Qb = sp.bmat([[Q, c * G.T], [c * G, Z]], format="csr")
    return Mb, Pb, Qb, c


def arpack(fn, what, **kw):
    """``fn`` (eigsh or eigs) from a fixed start vector: a pseudo-random one of a fixed seed,
    so that a case lists the same vectors in the same order on every run (ARPACK's own start
    differs between runs: the two members of a degenerate pair came out in either order).
    Not all ones: that vector is orthogonal to every antisymmetric mode of a symmetric model."""
    if kw.get("v0") is None:
        kw["v0"] = np.random.default_rng(0).standard_normal(kw["A"].shape[0])
    try:
        return fn(**kw)
    except spla.ArpackNoConvergence as exc:
        got = 0 if exc.eigenvalues is None else len(exc.eigenvalues)
        raise SolverError(f"{what}: ARPACK did not converge ({got} of {kw.get('k')} eigenvalues "
                          f"after {kw.get('maxiter') or 'default'} iterations); ask for fewer "
                          f"modes, move the target or raise maxiter") from None
    except spla.ArpackError as exc:
        raise SolverError(f"{what}: ARPACK failed: {exc}") from None


def undamped_partial(Mb, Qb, k, sigma, scale, ncv, maxiter, tol, purify, lu=None):
    """k eigenpairs (ω², v) of Q v = ω² M v nearest σ (Lanczos, shift-invert mode), purified
    when M is singular (bordered), and the shift actually used; ``lu``: a :class:`ShiftLU` of
    Q − σM already made (else one is made here)."""
    nb = Mb.shape[0]
    lu = lu if lu is not None else ShiftLU(Mb, None, Qb, sigma, scale, quadratic=False)
    OPinv = spla.LinearOperator((nb, nb), matvec=lambda x: lu.solve(np.asarray(x).ravel()),
                                dtype=float)
    w, V = arpack(spla.eigsh, "partial-eigh", A=Qb, k=k, M=Mb, sigma=lu.sigma, which="LM",
                   OPinv=OPinv, ncv=ncv, maxiter=maxiter, tol=tol)
    if purify:  # v ← (Q − σM)⁻¹ M v: the component along M's null space (multipliers) is removed
        V = lu.solve(np.asarray(Mb @ V))
        mv = np.sqrt(np.abs(np.einsum("ij,ij->j", V, Mb @ V)))
        V = V / np.where(mv > 0, mv, 1.0)
    return w, V, lu.sigma


def companion_partial(Mb, Pb, Qb, k, sigma, scale, ncv, maxiter, tol, purify):
    """k eigenpairs of the companion pencil nearest σ in the s-plane (Arnoldi, shift-invert):
    (s, first halves, second halves / s, coverage (σ, ν_min, real_part)).

    A complex σ on real matrices runs real Arnoldi on the real part of the shift-invert operator,
    Re (A − σB)⁻¹B, whose eigenvalues ν = ½[1/(s − σ) + 1/(s − σ̄)] are largest for s near σ
    or σ̄ (Parlett & Saad 1987; complex Arnoldi is two orders slower here); s is recovered from
    each Ritz vector by one application of the complex operator.  Every eigenvalue not returned
    has |ν| ≤ ν_min, which is what the coverage test uses."""
    nb = Mb.shape[0]
    lu = ShiftLU(Mb, Pb, Qb, sigma, scale)
    sig = lu.sigma
    PsM = (Pb + sig * Mb).tocsr()
    real_part = bool(np.iscomplex(sig))

    def op(v):
        v = np.asarray(v)
        v1, v2 = v[:nb], v[nb:]
        b = np.asarray(Mb @ v2 + PsM @ v1)
        z1 = -lu.solve(b.astype(np.result_type(b, complex if real_part else float)))
        return np.concatenate([z1, v1 + sig * z1])

    if real_part:
        OP = spla.LinearOperator((2 * nb, 2 * nb), matvec=lambda v: op(v).real, dtype=float)
    else:
        OP = spla.LinearOperator((2 * nb, 2 * nb), matvec=op, dtype=float)
    nu, Z = arpack(spla.eigs, "partial-companion", A=OP, k=k, which="LM", ncv=ncv,
                    maxiter=maxiter, tol=tol)
    ok = nu != 0
    nu, Z = nu[ok], Z[:, ok]
    nu_min = float(np.min(np.abs(nu))) if nu.size else np.inf
    if real_part or purify:  # (A − σB)⁻¹B once more: s from the Ritz vector, and purified
        W = np.empty(Z.shape, dtype=complex)  # filled column by column: no list of copies
        for j in range(Z.shape[1]):
            W[:, j] = op(Z[:, j])
        with np.errstate(divide="ignore", invalid="ignore"):
            mu = np.einsum("ij,ij->j", Z.conj(), W) / np.einsum("ij,ij->j", Z.conj(), Z)
        Z = W
        del W
    else:
        mu = nu
    s = sig + 1.0 / mu
    return s, Z[:nb], Z[nb:] / np.where(s != 0, s, 1.0), (complex(sig), nu_min, real_part)


def left_vectors(Mb, Pb, Qb, s, steps=3):
    """Conjugated left eigenvectors ȳ, (s²Mᵀ + sPᵀ + Qᵀ) ȳ = 0, by inverse iteration at each
    eigenvalue (one sparse LU each; a conjugate partner takes the conjugate)."""
    nb = Mb.shape[0]
    Y = np.empty((nb, s.size), complex)
    Mt, Pt, Qt = Mb.T.tocsc(), Pb.T.tocsc(), Qb.T.tocsc()
    rng = np.random.default_rng(11)
    for j, z in enumerate(s):
        partner = [i for i in range(j) if s[i] == np.conj(z)]
        if partner:
            Y[:, j] = np.conj(Y[:, partner[0]])
            continue
        lu = None
        for rel in (1e-13, 1e-11, 1e-9):  # exactly singular at the eigenvalue: step off it
            zz = z * (1 + rel) + rel
            try:
                lu = spla.splu((zz * zz * Mt + zz * Pt + Qt).tocsc())
                break
            except RuntimeError:
                continue
        if lu is None:
            raise SolverError(f"left eigenvector of s = {z:.6g}: every factorization near it "
                              f"is singular")
        y = rng.standard_normal(nb) + 1j * rng.standard_normal(nb)
        for _ in range(steps):
            y = lu.solve(y / np.linalg.norm(y))
        Y[:, j] = y / np.linalg.norm(y)
    return Y
