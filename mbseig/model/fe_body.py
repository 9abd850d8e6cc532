"""Linear reduced FE bodies (Craig–Bampton or modal) and their export from a beam model.

A body is linear about its reference configuration (small motion, no geometric stiffness):
U = ½ zᵀ K z, T = ½ żᵀ M ż with z = C q + d, z = [interface dofs; modal coordinates]
(docs/design.md, "Flexible bodies").
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import CaseError
from .affine import Affine
from .base import Force
from .fe_reduction import craig_bampton, write_matrices

__all__ = ["LinearFEBody", "craig_bampton", "export_fe_body", "write_matrices"]


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


def export_fe_body(model, interface, path, *, n_modes=None, q=None, lam=None):
    """Write a model (typically one free-free beam) as a Craig–Bampton FE body.

    interface : point names; each contributes (P.x, P.y, θ) with θ the angle coordinate of the
        beam node at P (in 3-D: u_x, u_y, u_z, θ_x, θ_y, θ_z, :mod:`mbseig.model.fe_body3d`).
        The matrices are M(q) and K(q) + Σλ∇²Φ at q (default the initial
        positions), on the model's coordinates when it has no constraints.  ``path`` ending in
        .npz gets arrays ``M`` and ``K``; ending in .mtx gives ``<stem>_M.mtx`` and
        ``<stem>_K.mtx`` (MatrixMarket).  Returns the written file names.
    """
    if getattr(model, "dimension", 2) == 3:  # 6 rows per interface point (fe_body3d)
        from .fe_body3d import export_fe_body_3d

        return export_fe_body_3d(model, interface, path, n_modes=n_modes, q=q)
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
    return write_matrices(path, Mr, Kr)
