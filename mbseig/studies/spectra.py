"""The modes of many linear models at once: the eigen stage, the error bounds and the stability
of every point of a sweep line (or of one point: a batch of one), with a batch axis.

:func:`point_spectra` takes the linear models of the points and returns, per point, every
eigenvalue, the unit mode shapes in full coordinates, the stability tolerance of each
eigenvalue, the verdict and the solver.  The small dense real models (order ≤ BATCH_MAX) are
grouped by order and solved together (:func:`mbseig.eigen.batch.solve_batch`,
:func:`mbseig.modal.batch.batch_tolerances`); a model the batch does not cover (larger, sparse
beyond BATCH_MAX, complex, a mass matrix that is not symmetric positive definite, a pair the
batch cannot verify) takes the general driver on its own (:func:`mbseig.eigen.solve` and
:func:`mbseig.modal.tolerances`), which the batch records as its reason.  Both give the verdict
by the same rule (:func:`mbseig.modal.scope.spectrum_verdict`: rigid-body modes left out only
where they span the declared rigid directions).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from ..eigen import Problem, Request, solve
from ..eigen.batch import solve_batch
from ..errors import MbseigError
from ..linear import declare_many
from ..modal import classify, tolerances
from ..modal.batch import batch_tolerances
from ..modal.scope import spectrum_verdict, spectrum_verdicts

__all__ = ["PointSpectrum", "point_spectra", "BATCH_MAX"]

#: largest order of a model solved in a batch: up to it a stacked eig of the companion (2n)²
#: costs no more than LAPACK's own call per problem (measured: 26 µs at n = 6, one BLAS thread);
#: above it each model takes the general driver, one at a time, through the same function
BATCH_MAX = 64


@dataclass
class PointSpectrum:
    """One point's modes: eigenvalues, unit shapes in full coordinates, tolerances, verdict
    (a :class:`~mbseig.modal.result.Verdict`), solver (the path; ``batched`` where the batch
    solved it), rigid (per eigenvalue: classified rigid-body, s = 0 within its error)."""

    eigenvalues: np.ndarray
    shapes: np.ndarray
    tol: np.ndarray
    verdict: object
    solver: str
    rigid: np.ndarray | None = None


def _dense(A):
    return A.toarray() if sp.issparse(A) else A


def _batchable(lin):
    n = lin.M.shape[0]
    if not 0 < n <= BATCH_MAX:
        return False
    for A in (lin.M, lin.P, lin.Q):
        if A is not None and (np.iscomplexobj(A) or A.shape != (n, n)):
            return False
    return True


def _shapes(N, X):
    Xf = N @ X
    return Xf / np.maximum(np.linalg.norm(Xf, axis=0), np.finfo(float).tiny)


def _one(lin, safety, stability_rtol):
    """The general driver's modes of one linear model."""
    sol = solve(Problem(lin.M, lin.P, lin.Q), Request())
    s = sol.eigenvalues
    _, _, tol, rigid = tolerances(sol, safety=safety, stability_rtol=stability_rtol)
    v = spectrum_verdict(classify(-s.real, tol, rigid), rigid, sol.vectors, lin.rigid, lin.N)
    return PointSpectrum(s, _shapes(lin.N, sol.vectors), tol, v, sol.solver,
                         np.asarray(rigid, bool))


def _none(lin):
    n = lin.N.shape[0]
    return PointSpectrum(np.zeros(0, complex), np.zeros((n, 0), complex), np.zeros(0),
                         "stable", "none (no degree of freedom)", np.zeros(0, bool))


def point_spectra(lins, *, safety=10.0, stability_rtol=1e-12) -> list:
    """Per linear model of ``lins`` its :class:`PointSpectrum` (module docstring); an entry
    that is an exception instance stays that exception (a point whose statics failed), and a
    model whose eigen stage fails (:class:`~mbseig.errors.MbseigError`) gets that exception."""
    out = [None] * len(lins)
    groups: dict = {}
    for i, lin in enumerate(lins):
        if isinstance(lin, BaseException):
            out[i] = lin
        elif lin.M.shape[0] == 0:
            out[i] = _none(lin)
        elif _batchable(lin):
            groups.setdefault(lin.M.shape[0], []).append(i)
        else:
            out[i] = lin  # the general driver, below
    for n, members in groups.items():
        M = np.stack([np.asarray(_dense(lins[i].M), float) for i in members])
        P = np.stack([np.zeros((n, n)) if lins[i].P is None
                      else np.asarray(_dense(lins[i].P), float) for i in members])
        Q = np.stack([np.asarray(_dense(lins[i].Q), float) for i in members])
        sol = solve_batch(M, P, Q)
        bb = batch_tolerances(sol, M, P, Q, safety=safety, stability_rtol=stability_rtol)
        # the declared directions of every model that will ask (a rigid-body eigenvalue), at once
        declare_many([lins[i].rigid for j, i in enumerate(members)
                      if sol.covered[j] and bb.rigid[j].any()])
        cov = np.flatnonzero(sol.covered)
        verdicts = spectrum_verdicts(bb.stability[cov], bb.rigid[cov], sol.vectors[cov],
                                     [lins[members[j]].rigid for j in cov],
                                     [lins[members[j]].N for j in cov])
        verdicts = dict(zip(cov.tolist(), verdicts, strict=True))
        for j, i in enumerate(members):
            lin = lins[i]
            if not sol.covered[j]:
                out[i] = lin
                continue
            s, X = sol.eigenvalues[j], sol.vectors[j]
            out[i] = PointSpectrum(s, _shapes(lin.N, X), bb.tol_re[j], verdicts[j],
                                   f"{sol.solver[j]} (batched)", bb.rigid[j].copy())
    for i, x in enumerate(out):
        if x is lins[i] and not isinstance(x, BaseException):
            try:
                out[i] = _one(x, safety, stability_rtol)
            except MbseigError as exc:
                out[i] = exc
    return out
