"""Linear reduced FE bodies (Craig–Bampton or modal) and their export from a beam model.

A body is linear about its reference configuration (small motion, no geometric stiffness):
U = ½ zᵀ K z, T = ½ żᵀ M ż with z = C q + d, z = [interface dofs; modal coordinates]
(docs/design.md, "Flexible bodies").
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import scipy.linalg as sla

from ..errors import CaseError
from .affine import Affine
from .base import Force

__all__ = ["LinearFEBody", "craig_bampton", "export_fe_body"]


@dataclass(frozen=True, eq=False)
class LinearFEBody(Force):
    """Linear reduced FE body: U = ½ zᵀ K z with z = C q[idx] + d (module docstring)."""

    name: str
    z: Affine
    K: np.ndarray

    affine_field = "z"  # idx = z.idx

    def force(self, q, qd):
        return -(self.z.C.T @ (self.K @ self.z(q)))

    def jacobians(self, q, qd):
        m = self.idx.size
        return self.z.C.T @ self.K @ self.z.C, np.zeros((m, m))


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
    _, Phi = sla.eigh(Kii, M[np.ix_(i, i)], subset_by_index=[0, k - 1]) if k else (None, np.zeros((i.size, 0)))
    T = np.zeros((n, b.size + k))
    T[b, :b.size] = np.eye(b.size)
    T[np.ix_(i, np.arange(b.size))] = Psi
    T[np.ix_(i, np.arange(b.size, b.size + k))] = Phi
    Mr, Kr = T.T @ M @ T, T.T @ K @ T
    return 0.5 * (Mr + Mr.T), 0.5 * (Kr + Kr.T), T


def export_fe_body(model, interface, path, *, n_modes=None, q=None, lam=None):
    """Write a model (typically one free-free beam) as a Craig–Bampton FE body.

    interface : point names; each contributes (P.x, P.y, θ) with θ the angle coordinate of the
        beam node at P.  The matrices are M(q) and K(q) + Σλ∇²Φ at q (default the initial
        positions), on the model's coordinates when it has no constraints.  ``path`` ending in
        .npz gets arrays ``M`` and ``K``; ending in .mtx gives ``<stem>_M.mtx`` and
        ``<stem>_K.mtx`` (MatrixMarket).  Returns the written file names.
    """
    if model.n_constraints:
        raise CaseError("export_fe_body needs a model without constraints (a free body)",
                        element="export")
    q = model.q_init if q is None else q
    names = list(model.coordinate_names)
    beams = (model.flexible or {}).get("bodies", {})
    boundary = []
    for p in interface:
        for ax in ("x", "y"):
            if f"{p}.{ax}" not in names:
                raise CaseError(f"interface point {p!r} has no free coordinate {p}.{ax}",
                                element="export")
            boundary.append(names.index(f"{p}.{ax}"))
        theta = [f"{nm}.n{0 if r['points'][0] == p else r['elements']}.theta"
                 for nm, r in beams.items() if r.get("type") == "beam" and p in r["points"]]
        theta = [t for t in theta if t in names]
        if len(theta) != 1:
            raise CaseError(f"interface point {p!r} must be the end of exactly one beam with a "
                            "free rotation", element="export")
        boundary.append(names.index(theta[0]))
    M = model.mass_matrix(q).toarray()
    K = model.force_jacobians(q)[0].toarray()
    Mr, Kr, _ = craig_bampton(M, K, boundary, n_modes)
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
