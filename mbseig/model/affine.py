"""Affine maps from the coordinate vector: r = C q[idx] + d.

In natural coordinates every point of interest is an affine function of q: a free basic point
selects its own coordinates, a fixed point is a constant, and a point of a planar body with basic
points i, j and local coordinates (x̄, ȳ) is

    r_P = r_i + c1 (r_j − r_i) + c2 J (r_j − r_i),   c1 = x̄/L, c2 = ȳ/L,   J = [[0, −1], [1, 0]].

Directions carried by a body (r_j − r_i) and differences of points are affine too, so springs,
torsional springs, follower forces and constraints are all written on :class:`Affine` maps, and
their Jacobians are exact chain rules through the constant matrix C.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["Affine", "combine", "J2"]

J2 = np.array([[0.0, -1.0], [1.0, 0.0]])


@dataclass(frozen=True, eq=False)
class Affine:
    """r = C @ q[idx] + d  (C: dim × len(idx), d: dim)."""

    idx: np.ndarray
    C: np.ndarray
    d: np.ndarray

    @property
    def dim(self) -> int:
        return self.C.shape[0]

    def __call__(self, q: np.ndarray) -> np.ndarray:
        return self.C @ q[self.idx] + self.d

    def rate(self, qd: np.ndarray) -> np.ndarray:
        """Time derivative ṙ = C q̇[idx]."""
        return self.C @ qd[self.idx]

    def __sub__(self, other: "Affine") -> "Affine":
        return combine([(1.0, self), (-1.0, other)])

    @staticmethod
    def constant(value) -> "Affine":
        value = np.asarray(value, dtype=float)
        return Affine(np.zeros(0, dtype=np.intp), np.zeros((value.size, 0)), value.copy())

    @staticmethod
    def select(indices, fixed_values=None) -> "Affine":
        """A point whose coordinates are q[indices] (indices < 0 mark fixed components)."""
        indices = np.asarray(indices, dtype=np.intp)
        free = indices >= 0
        C = np.eye(indices.size)[:, free]
        d = np.zeros(indices.size) if fixed_values is None else np.where(free, 0.0, fixed_values)
        return Affine(indices[free], C, d)


def combine(terms, *, stack: bool = False) -> Affine:
    """Σ_k A_k r_k over (matrix-or-scalar, Affine) terms, or the vertical stack of the maps.

    The result acts on the union of the terms' coordinate indices.
    """
    idx = np.unique(np.concatenate([t[1].idx for t in terms])) if terms else np.zeros(0, np.intp)
    pos = {int(k): i for i, k in enumerate(idx)}
    blocks_C, blocks_d = [], []
    for factor, aff in terms:
        factor = np.asarray(factor, dtype=float)
        F = factor * np.eye(aff.dim) if factor.ndim == 0 else factor
        C = np.zeros((F.shape[0], idx.size))
        cols = [pos[int(k)] for k in aff.idx]
        C[:, cols] = F @ aff.C
        blocks_C.append(C)
        blocks_d.append(F @ aff.d)
    if stack:
        return Affine(idx, np.vstack(blocks_C), np.concatenate(blocks_d))
    return Affine(idx, sum(blocks_C), sum(blocks_d))
