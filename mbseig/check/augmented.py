"""[[M(q), Φ_qᵀ], [Φ_q, 0]] of the check's stiff right-hand side refilled on a fixed pattern.

``sp.bmat`` of the blocks costs about 1 ms a call at 24 beam elements; this forms the same CSC
matrix (same stored entries, order and values: M(q)'s zeros dropped, Φ_q's kept, as bmat does
with ``Model.mass_matrix(q)`` and ``Model.phi_q(q)``) by one gather, so that SuperLU orders and
factors the very same matrix (tests/test_check_rhs.py compares them array by array).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

__all__ = ["AugmentedPattern"]


class AugmentedPattern:
    """The augmented matrix of :class:`~mbseig.check.dynamics.ForwardDynamics` on a fixed
    pattern: where each stored entry of bmat's matrix comes from
    (found by forming it once from the source positions as values)."""

    def __init__(self, Mf, Js):
        self.keys = [(x.indptr.copy(), x.indices.copy()) for x in (Mf, Js)]
        nm, nj = Mf.nnz, Js.nnz

        def ids(x, start):
            return sp.csr_matrix(
                (np.arange(start, start + x.nnz, dtype=float), x.indices, x.indptr),
                shape=x.shape)

        A = sp.bmat([[ids(Mf, 1), ids(Js, nm + 1).T], [ids(Js, nm + nj + 1), None]], format="csc")
        self.src = A.data.astype(np.intp) - 1  # into [M.data, Φ_q.data, Φ_q.data]
        self.in_m = self.src < nm
        self.col = np.repeat(np.arange(A.shape[1]), np.diff(A.indptr))
        self.indices, self.indptr, self.shape = A.indices, A.indptr, A.shape

    def matches(self, Mf, Js):
        return all(np.array_equal(p, x.indptr) and np.array_equal(i, x.indices)
                   for (p, i), x in zip(self.keys, (Mf, Js), strict=True))

    def fill(self, Mf, Js):
        data = np.concatenate([Mf.data, Js.data, Js.data])[self.src]
        keep = ~self.in_m | (data != 0.0)  # bmat stores no zero of M(q) (mass_matrix's sum)
        if keep.all():
            return sp.csc_matrix((data, self.indices.copy(), self.indptr.copy()), shape=self.shape)
        indptr = np.zeros_like(self.indptr)
        np.cumsum(np.bincount(self.col[keep], minlength=self.shape[1]), out=indptr[1:])
        return sp.csc_matrix((data[keep], self.indices[keep], indptr), shape=self.shape)
