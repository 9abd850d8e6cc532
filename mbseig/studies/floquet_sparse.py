"""Coefficient matrices of a periodic linearization on their nonzero pattern.

The sampled C(t), K(t) of a multibody model (:mod:`mbseig.studies.periodic`) are sparse: each
force and constraint couples a few coordinates.  :class:`PatternSeries` holds the trigonometric
series of the entries that are nonzero at some sample only, and the entries that do not change
with time once: evaluating it at t costs O(nnz_t) for the time-dependent entries, not O(N n²), and
gives a CSR matrix, so that the projections Nᵀ K N of
:func:`~mbseig.studies.floquet_paths.constrained_system` cost O(nnz r + n r²) instead of
O(n² r).  A matrix that is zero at every sample is held as None (no product at all); a dense
one stays a dense array.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ..model.timed import TrigSeries

__all__ = ["DENSE_FRACTION", "PatternSeries", "as_operator", "pattern_series"]

DENSE_FRACTION = 0.25  # above this fraction of nonzero entries a matrix is kept dense


class PatternSeries:
    """A(t) on a fixed pattern: ``A(t, order)`` (order 0, 1, 2 as for
    :class:`~mbseig.model.timed.TrigSeries`) is a CSR matrix, a dense array or None (zero)."""

    def __init__(self, shape, rows, cols, constant, moving, series, dense):
        self.shape = shape
        self.rows, self.cols = rows, cols  # row-major (np.nonzero): the CSR order
        if rows is not None:
            self.indptr = np.concatenate([[0], np.cumsum(np.bincount(rows, minlength=shape[0]))])
        self.constant = constant  # values of every pattern entry at the constant part
        self.moving = moving  # indices (into the pattern) of the entries that change with t
        self.series = series  # TrigSeries of those entries (or None)
        self.dense = dense  # a dense TrigSeries when the pattern is not sparse

    def __call__(self, t, order=0):
        if self.dense is not None:
            return self.dense(t, order)
        if self.rows.size == 0:
            return None
        data = self.constant.copy() if order == 0 else np.zeros_like(self.constant)
        if self.series is not None:
            data[self.moving] = self.series(t, order)
        return sp.csr_matrix((data, self.cols, self.indptr), shape=self.shape, copy=False)


def pattern_series(samples, period, *, offset=0.0):
    """The :class:`PatternSeries` of matrices sampled at N equally spaced instants from
    ``offset`` (the same samples as :meth:`TrigSeries.fit`)."""
    samples = np.asarray(samples, dtype=float)
    shape = samples.shape[1:]
    nz = np.any(samples != 0.0, axis=0)
    if nz.sum() > DENSE_FRACTION * nz.size:
        return PatternSeries(shape, None, None, None, None, None,
                             TrigSeries.fit(samples, period, offset=offset))
    rows, cols = np.nonzero(nz)
    values = samples[:, rows, cols]  # (N, nnz)
    moves = np.any(values != values[0], axis=0)
    moving = np.nonzero(moves)[0]
    series = TrigSeries.fit(values[:, moving], period, offset=offset) if moving.size else None
    return PatternSeries(shape, rows, cols, values[0].copy(), moving, series, None)


def as_operator(matrix):
    """A constant matrix as CSR when it is sparse enough, else as a dense array."""
    A = np.asarray(matrix, dtype=float)
    if np.count_nonzero(A) <= DENSE_FRACTION * A.size:
        return sp.csr_matrix(A)
    return A
