"""A sparse matrix applied to the dense blocks of the partial paths by real products
(:mod:`mbseig.eigen.projected`): no complex copy of the matrix, no layout conversion of the
block."""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

__all__ = ["BlockOp"]


class BlockOp:
    """A sparse matrix applied to real or complex blocks by real products (a diagonal one as a
    scaling): no complex copy of the matrix, no layout conversion of the block."""

    def __init__(self, A):
        self.A = A
        off = A - sp.diags(A.diagonal(), format="csr")
        self.d = A.diagonal()[:, None] if not np.any(off.data) else None

    @property
    def T(self):
        return BlockOp(self.A.T.tocsr())

    def __matmul__(self, V):
        if V.ndim == 1:
            return self.A @ V
        if np.iscomplexobj(V):
            out = np.empty((self.A.shape[0], V.shape[1]), complex, order="F")
            self._real(V.real, out.real)
            self._real(V.imag, out.imag)
            return out
        if self.d is not None:
            return self.d * V
        if V.flags.c_contiguous:
            return self.A @ V
        out = np.empty((self.A.shape[0], V.shape[1]), order="F")
        self._real(V, out)
        return out

    def _real(self, V, out):
        """out = A V for a real block V (any layout), column by column where A is sparse: a
        block product would first copy a column-major V to row-major (scipy's layout), a
        transposition that cost more than the product at 10⁶ rows; the sums are the same."""
        if self.d is not None:
            np.multiply(self.d, V, out=out)
            return
        for j in range(V.shape[1]):
            out[:, j] = self.A @ np.ascontiguousarray(V[:, j])
