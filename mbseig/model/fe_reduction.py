"""Craig–Bampton reduction of a structural model to interface coordinates plus fixed-interface
modes, and writing reduced matrices as an FE body file (.npz or MatrixMarket); used by the 2-D
and 3-D exports."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import scipy.linalg as sla

from ..errors import CaseError


# ---------------------------------------------------------------------------------------------
def craig_bampton(M, K, boundary, n_modes=None):
    """Craig–Bampton reduction of (M, K) keeping the ``boundary`` dofs physical.

        q = T [u_b; η],   T = ┌ I    0 ┐,   Ψ = −K_ii⁻¹ K_ib (static constraint modes),
                              └ Ψ    Φ ┘    Φ: the lowest ``n_modes`` fixed-interface modes

    (all of them when None: then T is square and the reduction exact).  Returns (Tᵀ M T, Tᵀ K T, T)
    with the boundary dofs first, in the order given.
    """
    M, K = np.asarray(M, dtype=float), np.asarray(K, dtype=float)
    n = M.shape[0]
    b = np.asarray(boundary, dtype=np.intp)
    i = np.setdiff1d(np.arange(n), b)
    Kii, Kib = K[np.ix_(i, i)], K[np.ix_(i, b)]
    Psi = -np.linalg.solve(Kii, Kib)
    k = i.size if n_modes is None else min(int(n_modes), i.size)
    _, Phi = (sla.eigh(Kii, M[np.ix_(i, i)], subset_by_index=[0, k - 1]) if k
              else (None, np.zeros((i.size, 0))))
    T = np.zeros((n, b.size + k))
    T[b, :b.size] = np.eye(b.size)
    T[np.ix_(i, np.arange(b.size))] = Psi
    T[np.ix_(i, np.arange(b.size, b.size + k))] = Phi
    Mr, Kr = T.T @ M @ T, T.T @ K @ T
    return 0.5 * (Mr + Mr.T), 0.5 * (Kr + Kr.T), T


def write_matrices(path, Mr, Kr):
    """Write reduced M and K: ``path`` ending in .npz gets arrays ``M`` and ``K``; ending in
    .mtx gives ``<stem>_M.mtx`` and ``<stem>_K.mtx`` (MatrixMarket).  Returns the file names."""
    path = Path(path)
    if path.suffix == ".npz":
        np.savez(path, M=Mr, K=Kr)
        return [str(path)]
    if path.suffix == ".mtx":
        import scipy.io

        out = []
        for key, A in (("M", Mr), ("K", Kr)):
            f = path.with_name(f"{path.stem}_{key}.mtx")
            scipy.io.mmwrite(str(f), A, symmetry="symmetric")
            out.append(str(f))
        return out
    raise CaseError(f"export to .npz or .mtx, got {path.name!r}", element="export")
