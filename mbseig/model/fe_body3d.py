"""Reduced FE bodies in 3-D: the 6-per-node matrices of a spatial beam model and their export
(DESIGN §8, "3-D flexible bodies and flexible rotors"; docs/beams3d.md, "FE bodies in 3-D").

A 3-D beam model carries each node as a point r and three unit vectors e₁, e₂, e₃ (equal to the
global axes at the reference, :mod:`mbseig.casefile.flexible3d`).  About the reference, a small
motion of a node is a translation u and a small rotation θ (global axes):

    δr = u,    δeᵢ = θ × eᵢ = −[eᵢ]ₓ θ,

which satisfies the rigid-triad conditions to first order.  Stacking these maps for every point
and every free triad gives q − q₀ = Q y, y = [u, θ per node]; the FE matrices are
M₆ = Qᵀ M(q₀) Q and K₆ = Qᵀ (K(q₀) + Σλ∇²Φ) Q (:func:`node_matrices`).  They are the assembled
standard 12×12 elements of the beams (Nelson 1980) in global axes; an exported body built from
them (:func:`export_fe_body_3d`, Craig–Bampton with the interface points' 6 rows first) has the
modes of the beam model itself.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import CaseError

__all__ = ["NodeMatrices", "export_fe_body_3d", "node_matrices"]


def _cross(e) -> np.ndarray:
    x, y, z = e
    return np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])


@dataclass(frozen=True, eq=False)
class NodeMatrices:
    """Mass and stiffness of a free 3-D beam model on y = [u, θ] per node (module docstring):
    ``labels`` name the rows (``P.u_x`` … ``P.theta_z``; a node is its point's name, or
    ``BEAM.nK`` inside a beam), ``Q`` maps y to the model's coordinates."""

    M: np.ndarray
    K: np.ndarray
    Q: np.ndarray
    labels: tuple

    def rows(self, node: str) -> list[int]:
        """The 6 rows (u_x, u_y, u_z, θ_x, θ_y, θ_z) of ``node``."""
        want = [f"{node}.u_{a}" for a in "xyz"] + [f"{node}.theta_{a}" for a in "xyz"]
        missing = [w for w in want if w not in self.labels]
        if missing:
            raise CaseError(f"interface point {node!r} has no free {missing[0].split('.')[-1]} "
                            "(it must be the free end of exactly one beam)", element="export")
        return [self.labels.index(w) for w in want]


def node_matrices(model, q=None, lam=None) -> NodeMatrices:
    """M₆, K₆ of a 3-D beam model on its nodes' translations and small rotations (module
    docstring) at ``q`` (default the initial positions; ``lam`` the multipliers there, default
    zero: an unloaded body).  Every coordinate must be a point or a node triad, and every
    constraint one that the parametrization keeps (the rigid triads): a free body."""
    if getattr(model, "dimension", 2) != 3:
        raise CaseError("node_matrices needs a 3-D model", element="export")
    q = np.asarray(model.q_init if q is None else q, float)
    names = list(model.coordinate_names)
    index = {nm: i for i, nm in enumerate(names)}
    beams = (model.flexible or {}).get("bodies", {})
    at_point = {}  # triad prefix of a beam end node → the end's point name
    for rec in beams.values():
        if rec.get("type") == "beam" and rec.get("dimension") == 3:
            at_point[rec["nodes"][0]] = rec["points"][0]
            at_point[rec["nodes"][-1]] = rec["points"][1]
    cols, labels, used = [], [], set()
    n = len(names)
    for _i, nm in enumerate(names):
        if nm in used:
            continue
        if nm.endswith(".u.x"):
            pre = nm[:-4]
            idx = [index.get(f"{pre}.{v}.{a}") for v in "uvw" for a in "xyz"]
            if None in idx:
                raise CaseError(f"coordinate {nm!r}: an incomplete node triad", element="export")
            E = q[idx].reshape(3, 3)
            node = at_point.get(pre, pre)
            for a in range(3):
                c = np.zeros(n)
                ea = np.eye(3)[a]
                for k in range(3):  # δe_k = θ × e_k, θ = e_a
                    c[idx[3 * k:3 * k + 3]] = np.cross(ea, E[k])
                cols.append(c)
                labels.append(f"{node}.theta_{'xyz'[a]}")
            used.update(names[j] for j in idx)
        elif nm.endswith(".x") and f"{nm[:-2]}.y" in index and f"{nm[:-2]}.z" in index:
            pre = nm[:-2]
            for a in "xyz":
                c = np.zeros(n)
                c[index[f"{pre}.{a}"]] = 1.0
                cols.append(c)
                labels.append(f"{pre}.u_{a}")
                used.add(f"{pre}.{a}")
        else:
            raise CaseError(f"coordinate {nm!r} is neither a point nor a beam node's triad: "
                            "export a model of beams only", element="export")
    Q = np.array(cols).T
    if len(set(labels)) != len(labels):
        dup = next(lb for lb in labels if labels.count(lb) > 1)
        raise CaseError(f"{dup.rsplit('.', 1)[0]!r} carries two free rotations (two beams with "
                        "free ends meet there): weld them or clamp one", element="export")
    if model.n_constraints:
        G = model.phi_q(q, dense=True) @ Q
        scale = np.abs(model.phi_q(q, dense=True)).max()
        if np.abs(G).max() > 1e-10 * max(scale, 1.0):
            raise CaseError("export needs a free model (beams only, no joints, fixed points "
                            "or clamped ends)", element="export")
    M = Q.T @ model.mass_matrix(q).toarray() @ Q
    K = Q.T @ model.force_jacobians(q)[0].toarray() @ Q
    if lam is not None and model.n_constraints:
        K = K + Q.T @ model.constraint_hessian(q, lam, dense=True) @ Q
    return NodeMatrices(0.5 * (M + M.T), 0.5 * (K + K.T), Q, tuple(labels))


def export_fe_body_3d(model, interface, path, *, n_modes=None, q=None):
    """Write a free 3-D beam model as a Craig–Bampton FE body (``[[fe_bodies]]`` in 3-D):
    6 rows per interface point (u_x, u_y, u_z, θ_x, θ_y, θ_z, global axes at the reference),
    then ``n_modes`` fixed-interface modal coordinates (all of them when None: exact).
    ``path`` as :func:`mbseig.model.fe_body.export_fe_body` (.npz or .mtx)."""
    from .fe_reduction import craig_bampton, write_matrices

    nm = node_matrices(model, q)
    boundary = [r for p in interface for r in nm.rows(p)]
    Mr, Kr, _ = craig_bampton(nm.M, nm.K, boundary, n_modes)
    return write_matrices(path, Mr, Kr)
