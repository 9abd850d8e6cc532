"""Batched element kernels: one object for many identical elements, vectorized over the batch.

A repeated element of a case (``repeat = {i = [1, "n"]}``) becomes one batch instead of n
Python objects, so that building and assembling a model with 10⁶ coordinates takes seconds.
The physics is that of the single-element kernel in :mod:`mbseig.model.elements`
(:class:`~mbseig.model.elements.SpringDamper`), evaluated for all members at once:

    d = r_b − r_a,  g_a += f,  g_b −= f,
    1-D:  f = k (d − l0) + c ḋ                     (signed extension)
    n-D:  f = k (l − l0) e + c (e·ḋ) e,  l = |d|,  e = d/l

and the local Jacobians [[K_f, −K_f], [−K_f, K_f]] are scattered as COO triplets.
Besides ``add_force`` and ``jacobian_coo`` (used by :class:`~mbseig.model.Model`), a batch offers
the single-element interface ``idx``, ``force``, ``jacobians`` on the union of its coordinates.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
import scipy.sparse as sp

from ..errors import EquilibriumError
from .base import BatchForce, Force

__all__ = ["SpringDamperSet", "QuadraticGroup", "kernel_groups", "spring_forces",
           "spring_tangents"]


def _geometry(d, k, l0, label):
    """Length l = √(d·d) (complex-step safe) and direction e of each member; a zero length is
    allowed only for a zero free length (or no stiffness), with e = x̂."""
    length = np.sqrt(np.einsum("ij,ij->i", d, d))
    zero = length == 0.0
    bad = zero & (l0 != 0.0) & (k != 0.0)
    if np.any(bad):
        raise EquilibriumError("spring has zero length but a non-zero free length: its "
                               "direction is undefined", element=label(int(np.argmax(bad))))
    e = np.divide(d, length[:, None], out=np.zeros_like(d), where=~zero[:, None])
    e[zero, 0] = 1.0
    return length, e


def spring_forces(d, dd, k, l0, c, label):
    """Force f (nb, dim) of spring-dampers on their point a (−f on b), d = r_b − r_a.

    1-D: f = k (d − l0) + c ḋ (signed extension);  n-D: f = k (l − l0) e + c (e·ḋ) e.
    ``label(k)`` names member k in errors.  The one spring law of mbseig: the single element
    (:class:`~mbseig.model.elements.SpringDamper`) and the batch both call it.
    """
    if d.shape[1] == 1:
        return k[:, None] * (d - l0[:, None]) + c[:, None] * dd
    length, e = _geometry(d, k, l0, label)
    mag = k * (length - l0) + c * np.einsum("ij,ij->i", e, dd)
    return mag[:, None] * e


def spring_tangents(d, dd, k, l0, c, label):
    """(Kf, Cf) (nb, dim, dim): ∂f/∂d and ∂f/∂ḋ of :func:`spring_forces`."""
    nb, dim = d.shape
    if dim == 1:
        return k[:, None, None] * np.ones((nb, 1, 1)), c[:, None, None] * np.ones((nb, 1, 1))
    length, e = _geometry(d, k, l0, label)
    eye = np.eye(dim)[None]
    E = e[:, :, None] * e[:, None, :]
    Pn = eye - E
    safe = np.where(length > 0, length, 1.0)
    r = np.where(length > 0, l0 / safe, 0.0)[:, None, None]
    kk = k[:, None, None]
    Kf = kk * ((1.0 - r) * eye + r * E)
    edd = np.einsum("ij,ij->i", e, dd)[:, None, None]
    c_l = np.where(length > 0, c / safe, 0.0)[:, None, None]
    Kf = Kf + c_l * (np.einsum("ij,ijk->ik", dd, Pn)[:, None, :] * e[:, :, None] + edd * Pn)
    Kf = np.where((length > 0)[:, None, None], Kf, kk * eye)
    return Kf, c[:, None, None] * E


@dataclass(frozen=True, eq=False)
class SpringDamperSet(BatchForce, Force):
    """Springs/dashpots k, l0, c between points a and b, one row per member.

    ia, ib : (nb, dim) coordinate indices of the two points (−1: a fixed component whose value
        is in pa / pb).  ``labels[k]`` names member k in error messages.
    """

    name: str
    ia: np.ndarray
    ib: np.ndarray
    pa: np.ndarray
    pb: np.ndarray
    stiffness: np.ndarray
    free_length: np.ndarray
    damping: np.ndarray
    labels: tuple = ()

    @property
    def dim(self) -> int:
        return self.ia.shape[1]

    def __len__(self):
        return self.ia.shape[0]

    @cached_property
    def idx(self) -> np.ndarray:
        both = np.concatenate([self.ia.ravel(), self.ib.ravel()])
        return np.unique(both[both >= 0])

    def _gather(self, idx, fixed, v):
        return np.where(idx >= 0, v[np.maximum(idx, 0)], fixed)

    def _d(self, q, qd):
        d = self._gather(self.ib, self.pb, q) - self._gather(self.ia, self.pa, q)
        zero = np.zeros_like(self.pa)
        dd = self._gather(self.ib, zero, qd) - self._gather(self.ia, zero, qd)
        return d, dd

    def _label(self, k):
        return self.labels[k] if k < len(self.labels) else f"{self.name} [{k}]"

    def members(self, q, qd):
        """(d, ḋ, k, l0, c, label): the arguments of :func:`spring_forces` for every member."""
        return (*self._d(q, qd), self.stiffness, self.free_length, self.damping, self._label)

    def member_forces(self, q, qd):
        """f (nb, dim): the force of each member on its point a (−f on b)."""
        return spring_forces(*self.members(q, qd))

    def nonfinite_member(self, q, qd):
        d, dd, k, l0, c, label = self.members(q, qd)
        parts = (self.member_forces(q, qd), *spring_tangents(d, dd, k, l0, c, label))
        bad = np.logical_or.reduce([np.reshape(~np.isfinite(p), (len(self), -1)).any(axis=1)
                                    for p in parts])
        return label(int(np.argmax(bad))) if bad.any() else None

    def add_force(self, g, q, qd):
        f = self.member_forces(q, qd)
        for idx, sign in ((self.ia, 1.0), (self.ib, -1.0)):
            ok = idx >= 0
            np.add.at(g, idx[ok], sign * f[ok])

    def force(self, q, qd):
        g = np.zeros(q.shape[0])
        self.add_force(g, q, qd)
        return g[self.idx]

    def _local(self, q, qd):
        """(Kf, Cf): (nb, dim, dim) member Jacobians of f with respect to d and ḋ."""
        return spring_tangents(*self.members(q, qd))

    def jacobian_coo(self, q, qd):
        """((rows, cols, K values), (rows, cols, C values)) of K = −∂g/∂q, C = −∂g/∂q̇."""
        Kf, Cf = self._local(q, qd)
        loc = np.concatenate([self.ia, self.ib], axis=1)  # (nb, 2 dim)
        rows = np.broadcast_to(loc[:, :, None], loc.shape + (loc.shape[1],))
        cols = np.broadcast_to(loc[:, None, :], rows.shape)
        ok = (rows >= 0) & (cols >= 0)
        S = np.array([[1.0, -1.0], [-1.0, 1.0]])
        out = []
        for F in (Kf, Cf):
            B = np.einsum("ab,nij->naibj", S, F).reshape(rows.shape)
            out.append((rows[ok], cols[ok], B[ok]))
        return tuple(out)

    def jacobians(self, q, qd):
        """Dense (K, C) on ``idx`` (the single-element interface; small batches only)."""
        n = q.shape[0]
        (rk, ck, vk), (rc, cc, vc) = self.jacobian_coo(q, qd)
        K = sp.coo_matrix((vk, (rk, ck)), shape=(n, n)).toarray()
        C = sp.coo_matrix((vc, (rc, cc)), shape=(n, n)).toarray()
        ix = np.ix_(self.idx, self.idx)
        return K[ix], C[ix]


# ---------------------------------------------------------------------------------------------
# Many elements of one kind at once: spatial joints, rigid-body conditions and bushings
# ---------------------------------------------------------------------------------------------
# members from which a kind is evaluated at once (fewer: one by one).  Measured per call of Φ,
# Φ_q, γ, H: 2-4 members are 1.2-1.8x slower at once, 8 are 1.7-2x faster, 24 are 1.5-6x faster
GROUP_MIN = 8


def kernel_groups(elements) -> list:
    """[(positions, QuadraticGroup)] of the elements whose own class names a batched kernel
    (``kernel`` in the class body: QuadraticConstraint, QuadraticSpringDamper; a subclass
    evaluates itself), grouped by class and shapes, at least GROUP_MIN each."""
    keyed = {}
    for k, e in enumerate(elements):
        kind = type(e).__dict__.get("kernel")
        if kind is not None:
            rows = e.rows
            keyed.setdefault((type(e), rows.B.shape, rows.aff.C.shape), []).append(k)
    return [(np.array(pos), QuadraticGroup([elements[k] for k in pos]))
            for pos in keyed.values() if len(pos) >= GROUP_MIN]


def _stacked(arrays):
    """One array of equal arrays (shared: the array itself, flagged by a leading None axis)
    or of the members' arrays (views of one array are used as they lie).  Equal means the
    same object or the same bytes (the joints of a multi-span shaft: 686 equal 4×24×24
    matrices, each its own array)."""
    first = arrays[0]
    if all(a is first for a in arrays):
        return first[None]
    raw = first.tobytes()
    if all(a.shape == first.shape and a.dtype == first.dtype and a.tobytes() == raw
           for a in arrays):
        return first[None]
    base = first.base
    if (base is not None and base.shape == (len(arrays), *first.shape)
            and all(a.base is base and a.ctypes.data == base[k].ctypes.data
                    for k, a in enumerate(arrays))):
        return base
    return np.stack(arrays)


class QuadraticGroup:
    """Members (each with ``rows``, a QuadraticMap e = zᵀB z + b·z + c on z = C q[idx] + d) of
    one class and shapes, with their arrays stacked once: the element kernels of
    :class:`~mbseig.model.spatial_joints.QuadraticConstraint` and
    :class:`~mbseig.model.spatial_forces.QuadraticSpringDamper` evaluated for all at once
    (the same formulas; sums in another order, so equal to rounding)."""

    def __init__(self, members):
        maps = [m.rows for m in members]
        self.idx = np.stack([r.aff.idx for r in maps])
        # one matrix shared by every member (the frames' read-only identity: a beam of 10⁵
        # nodes) is kept once, a leading axis of 1 that einsum and matmul broadcast
        self.C = _stacked([r.aff.C for r in maps])
        self.d = np.stack([r.aff.d for r in maps])
        self.B, self.b, self.c = (_stacked([getattr(r, k) for r in maps]) for k in "Bbc")
        n_z, n_q = self.C.shape[1:]
        # maps that select their coordinates (frames of free bodies): C = I, products skipped
        self.unit = n_z == n_q and bool(np.all(self.C == np.eye(n_z)))
        self.Ct = np.ascontiguousarray(self.C.transpose(0, 2, 1))
        if isinstance(members[0], Force):  # spring-dampers (constraints have no stiffness)
            self.K = _stacked([m.stiffness for m in members])
            self.D = _stacked([m.damping for m in members])

    def _z(self, v, d=True):
        z = np.einsum("npm,nm->np", self.C, v[self.idx])
        return z + self.d if d else z

    def _values(self, z):
        Bz = np.einsum("nkij,nj->nki", np.broadcast_to(self.B, (z.shape[0], *self.B.shape[1:])), z)
        return Bz, np.einsum("nki,ni->nk", Bz, z) + np.einsum("nkp,np->nk", np.broadcast_to(
            self.b, (z.shape[0], *self.b.shape[1:])), z) + self.c

    def _grad(self, Bz):
        return 2.0 * Bz + self.b

    # -- constraints ---------------------------------------------------------------------
    def phi(self, q):
        return list(self._values(self._z(q))[1])

    def jac(self, q):
        Bz, _ = self._values(self._z(q))
        G = self._grad(Bz)
        return list(G if self.unit else G @ self.C)

    def hess(self, lam):
        """lam (n, k): the members' multipliers."""
        W = 2.0 * np.einsum("nk,nkij->nij", lam, np.broadcast_to(
            self.B, (lam.shape[0], *self.B.shape[1:])))
        return list(W if self.unit else self.Ct @ W @ self.C)

    def gamma(self, q, qd):
        zd = self._z(qd, d=False)
        Bzd, _ = self._values(zd)
        return list(-2.0 * np.einsum("nki,ni->nk", Bzd, zd))

    # -- spring-dampers on quadratic strains (QuadraticSpringDamper) ------------------------
    def _state(self, q, qd):
        z, zd = self._z(q), self._z(qd, d=False)
        Bz, e = self._values(z)
        G = self._grad(Bz)
        Gzd = np.einsum("nkp,np->nk", G, zd)
        f = np.einsum("nij,nj->ni", np.broadcast_to(self.K, (z.shape[0], *self.K.shape[1:])), e) \
            + np.einsum("nij,nj->ni", np.broadcast_to(self.D, (z.shape[0], *self.D.shape[1:])), Gzd)
        return zd, G, f

    def force(self, q, qd):
        _, G, f = self._state(q, qd)
        gz = np.einsum("nkp,nk->np", G, f)
        return list(-gz if self.unit else -np.einsum("npm,np->nm", self.C, gz))

    def jacobians(self, q, qd):
        zd, G, f = self._state(q, qd)
        nb = G.shape[0]
        B = np.broadcast_to(self.B, (nb, *self.B.shape[1:]))
        Gdot = 2.0 * np.einsum("nkij,nj->nki", B, zd)
        Gt = G.transpose(0, 2, 1)
        Kz = Gt @ (self.K @ G + self.D @ Gdot) + 2.0 * np.einsum("nk,nkij->nij", f, B)
        Cz = Gt @ self.D @ G
        if self.unit:
            return list(zip(Kz, Cz, strict=True))
        return list(zip(self.Ct @ Kz @ self.C, self.Ct @ Cz @ self.C, strict=True))
