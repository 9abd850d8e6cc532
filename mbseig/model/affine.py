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

import weakref
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

    def __sub__(self, other: Affine) -> Affine:
        return combine([(1.0, self), (-1.0, other)])

    @staticmethod
    def constant(value) -> Affine:
        value = np.asarray(value, dtype=float)
        return Affine(np.zeros(0, dtype=np.intp), np.zeros((value.size, 0)), value.copy())

    @staticmethod
    def select(indices, fixed_values=None) -> Affine:
        """A point whose coordinates are q[indices] (indices < 0 mark fixed components)."""
        indices = np.asarray(indices, dtype=np.intp)
        free = indices >= 0
        C = np.eye(indices.size)[:, free] if not free.all() else np.eye(indices.size)
        d = np.zeros(indices.size) if fixed_values is None else np.where(free, 0.0, fixed_values)
        return Affine(indices[free], C, d)


def combine(terms, *, stack: bool = False) -> Affine:
    """Σ_k A_k r_k over (matrix-or-scalar, Affine) terms, or the vertical stack of the maps.

    The result acts on the union of the terms' coordinate indices.
    """
    if not terms:
        idx = np.zeros(0, np.intp)
        return Affine(idx, np.zeros((0, 0)), np.zeros(0))
    if stack:
        fast = _stacked_in_order(terms)
        if fast is not None:
            return fast
    flat = np.concatenate([t[1].idx for t in terms])
    if flat.size <= 64:  # (a point, a direction, a pair of frames: the sorted set, cheaper)
        idx = np.array(sorted(set(flat.tolist())), dtype=np.intp)
    else:
        idx = np.unique(flat).astype(np.intp, copy=False)
    parts = []
    for factor, aff in terms:
        if type(factor) in (int, float) or np.ndim(factor) == 0:
            f = float(factor)
            parts.append((aff, f * aff.C, f * aff.d))
        else:
            F = np.asarray(factor, dtype=float)
            parts.append((aff, F @ aff.C, F @ aff.d))
    if stack:
        rows = sum(Cb.shape[0] for _, Cb, _ in parts)
        C, r = np.zeros((rows, idx.size)), 0
        for aff, Cb, _ in parts:
            C[r:r + Cb.shape[0], np.searchsorted(idx, aff.idx)] = Cb
            r += Cb.shape[0]
        return Affine(idx, C, np.concatenate([db for _, _, db in parts]))
    C = np.zeros((parts[0][1].shape[0], idx.size))
    d = np.zeros(parts[0][2].shape[0])
    for aff, Cb, db in parts:
        C[:, np.searchsorted(idx, aff.idx)] += Cb
        d += db
    return Affine(idx, C, d)


def _stacked_in_order(terms):
    """The stack of maps with unit factors whose indices follow each other in increasing order
    (a frame after another, a frame after the ground): the block diagonal of their matrices on
    the concatenated indices, the very matrix the general path places (or None: not this case)."""
    if not all(type(f) in (int, float) and f == 1 for f, _ in terms):
        return None
    idx = np.concatenate([a.idx for _, a in terms]).astype(np.intp, copy=False)
    if idx.size > 1 and not np.all(idx[1:] > idx[:-1]):
        return None
    d = np.concatenate([a.d for _, a in terms])
    if idx.size <= 64 and all(a.C is _EYES.get(a.idx.size) for _, a in terms):
        return Affine(idx, identity_of(idx.size), d)  # (shared identities: the shared one)
    rows = sum(a.C.shape[0] for _, a in terms)
    C, r, c = np.zeros((rows, idx.size)), 0, 0
    for _, a in terms:
        nr, nc = a.C.shape
        if nc != a.idx.size:
            return None
        C[r:r + nr, c:c + nc] = a.C
        r, c = r + nr, c + nc
    return Affine(idx, _identity_shared(C), d)


_EYES: dict = {}
_CONSTANTS = weakref.WeakValueDictionary()  # shared_constant's arrays, by their bytes


def shared_constant(A):
    """A read-only array with A's bytes, one per distinct value among those alive: equal
    constant matrices of many elements (the 686 joints of a multi-span shaft, 18 KB each)
    kept once.  ``A`` must be the caller's own fresh array (it is made read-only)."""
    A = np.ascontiguousarray(A)
    key = (A.shape, A.dtype.str, A.tobytes())
    got = _CONSTANTS.get(key)
    if got is None:
        A.setflags(write=False)
        _CONSTANTS[key] = got = A
    return got


def identity_of(n):
    """One read-only n × n identity, shared by every map whose matrix it is."""
    eye = _EYES.get(n)
    if eye is None:
        eye = np.eye(n)
        eye.setflags(write=False)
        _EYES[n] = eye
    return eye


def _identity_shared(C):
    """C itself, or where C is the identity the shared one of its size (:func:`identity_of`;
    the stacked frames of a beam element: its two nodes' own coordinates)."""
    n = C.shape[0]
    if C.shape[1] != n or n > 64:
        return C
    eye = identity_of(n)
    return eye if np.array_equal(C, eye) else C
