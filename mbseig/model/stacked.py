"""B models of one structure evaluated at once: the element kernels with a leading batch axis.

The models of a sweep line or a sample set differ in values (a load, a stiffness, a length, a
mass), not in structure: the same coordinates, the same elements on the same coordinates.
:class:`ModelStack` holds, for every element position, the B elements of that position stacked
into arrays (an element kernel of the batch: the same formulas as the element's own methods in
:mod:`mbseig.model.elements` and :mod:`mbseig.model.spatial_joints`, on arrays with a leading
axis of B), and evaluates g, K, C, Φ, Φ_q and H(λ) of all B models on the stacked coordinates
Q (B, n) as dense arrays:

    g (B, n),  K, C (B, n, n),  Φ (B, m),  Φ_q (B, m, n),  H (B, n, n),  M (B, n, n).

An element class without a batched kernel is evaluated by its own methods, one model at a time
(:class:`_Each`: ``force``/``jacobians`` on its coordinates, which a batch of repeated elements,
:class:`~mbseig.model.batched.SpringDamperSet`, also offers): the same numbers, at Python's cost
per model.  :func:`stackable` says why a
set of models cannot be stacked (different structure, a configuration-dependent mass, pending
inverse-statics commands, non-holonomic rows, a large model); the caller then takes each model
on its own.
"""

from __future__ import annotations

import copy

import numpy as np

from .elements import (
    DistanceConstraint,
    FollowerForce,
    LinearConstraint,
    SpringDamper,
    TorsionalSpringDamper,
)
from .batched import spring_forces, spring_tangents
from .rolling import WheelRows
from .spatial_joints import QuadraticConstraint

__all__ = ["ModelStack", "stackable", "STACK_MAX"]

#: largest n + m of a model evaluated in a stack (dense (B, n, n) arrays; above it a model's
#: sparse evaluations are cheaper than the batch's dense ones)
STACK_MAX = 400


def stackable(models) -> str | None:
    """None where ``models`` can be stacked, else why not (module docstring)."""
    m0 = models[0]
    if m0.n + m0.n_constraints > STACK_MAX:
        return f"{m0.n + m0.n_constraints} unknowns (above {STACK_MAX})"
    for m in models:
        if m.mass_elements:
            return "a configuration-dependent mass (co-rotational beams)"
        if m.velocity_constraints:
            return "rolling (non-holonomic) rows"
        if m.commands:
            return "inverse-statics commands pending"
        if (m.n != m0.n or len(m.forces) != len(m0.forces)
                or len(m.constraints) != len(m0.constraints)):
            return "models of different structure"
        for a, b in zip(m.forces + m.constraints, m0.forces + m0.constraints, strict=True):
            if a is b:
                continue
            if type(a) is not type(b) or a.idx is None or not np.array_equal(a.idx, b.idx):
                return "models of different structure"
    return None


def _stack(arrays):
    """(B, ...) of the members' arrays; (1, ...) where they are one object (broadcast)."""
    first = arrays[0]
    if all(a is first for a in arrays):
        return np.asarray(first, float)[None]
    return np.stack([np.asarray(a, float) for a in arrays])


def _affine(maps):
    return _stack([a.C for a in maps]), _stack([a.d for a in maps])


def _values(els, *fields):
    """(B,) arrays of the scalar ``fields`` of the members (one member: shape (1,), broadcast)."""
    return tuple(np.array([getattr(e, f) for e in els], float) for f in fields)


def _apply(C, d, Z):
    """r = C z + d per member: C (B|1, r, m), Z (B, m) → (B, r)."""
    return np.einsum("brm,bm->br", np.broadcast_to(C, (Z.shape[0], *C.shape[1:])), Z) + d


def _sandwich(C, A):
    """Cᵀ A C per member: C (B|1, r, m), A (B, r, r) → (B, m, m)."""
    Ct = np.swapaxes(C, 1, 2)
    return Ct @ A @ C


class _Each:
    """Any element, evaluated by its own methods one model at a time."""

    def __init__(self, elements):
        self.el = elements

    def phi(self, Z, Q):
        return np.stack([e.phi(q) for e, q in zip(self._e(Q), Q, strict=True)])

    def jac(self, Z, Q):
        return np.stack([e.jac(q) for e, q in zip(self._e(Q), Q, strict=True)])

    def hess(self, Z, Q, L):
        return np.stack([e.hess(q, lam) for e, q, lam in zip(self._e(Q), Q, L, strict=True)])

    def force(self, Z, Q):
        zero = np.zeros(Q.shape[1])
        return np.stack([e.force(q, zero) for e, q in zip(self._e(Q), Q, strict=True)])

    def jacobians(self, Z, Q):
        zero = np.zeros(Q.shape[1])
        got = [e.jacobians(q, zero) for e, q in zip(self._e(Q), Q, strict=True)]
        return np.stack([k for k, _ in got]), np.stack([c for _, c in got])

    def _e(self, Q):
        return self.el if len(self.el) == Q.shape[0] else self.el * Q.shape[0]


class _Distance:
    def __init__(self, els):
        self.C, self.d = _affine([e.diff for e in els])
        self.L2 = _stack([np.asarray(e.length, float) ** 2 for e in els])

    def phi(self, Z, Q):
        r = _apply(self.C, self.d, Z)
        return (np.einsum("br,br->b", r, r) - self.L2)[:, None]

    def jac(self, Z, Q):
        r = _apply(self.C, self.d, Z)
        return 2.0 * np.einsum("br,brm->bm", r, np.broadcast_to(
            self.C, (Z.shape[0], *self.C.shape[1:])))[:, None, :]

    def hess(self, Z, Q, L):
        CtC = np.swapaxes(self.C, 1, 2) @ self.C
        return 2.0 * L[:, 0, None, None] * CtC


class _Linear:
    def __init__(self, els):
        self.C, self.d = _affine([e.point for e in els])
        self.G, self.b = _stack([e.G for e in els]), _stack([e.b for e in els])
        self.m = els[0].idx.size

    def phi(self, Z, Q):
        r = _apply(self.C, self.d, Z)
        return np.einsum("bkr,br->bk", np.broadcast_to(self.G, (Z.shape[0], *self.G.shape[1:])),
                         r) - self.b

    def jac(self, Z, Q):
        return np.broadcast_to(self.G @ self.C, (Z.shape[0], self.G.shape[1], self.m))

    def hess(self, Z, Q, L):
        return np.zeros((Z.shape[0], self.m, self.m))


class _Quadratic:
    def __init__(self, els):
        self.C, self.d = _affine([e.aff for e in els])
        self.B = _stack([e.rows.B for e in els])
        self.bv = _stack([e.rows.b for e in els])
        self.c = _stack([e.rows.c for e in els])

    def _z(self, Z):
        return _apply(self.C, self.d, Z)

    def phi(self, Z, Q):
        z = self._z(Z)
        nb = z.shape[0]
        Bz = np.einsum("bkij,bj->bki", np.broadcast_to(self.B, (nb, *self.B.shape[1:])), z)
        return np.einsum("bki,bi->bk", Bz, z) + np.einsum(
            "bkp,bp->bk", np.broadcast_to(self.bv, (nb, *self.bv.shape[1:])), z) + self.c

    def jac(self, Z, Q):
        z = self._z(Z)
        nb = z.shape[0]
        G = 2.0 * np.einsum("bkij,bj->bki", np.broadcast_to(self.B, (nb, *self.B.shape[1:])), z) \
            + self.bv
        return G @ self.C

    def hess(self, Z, Q, L):
        nb = Z.shape[0]
        W = 2.0 * np.einsum("bk,bkij->bij", L, np.broadcast_to(self.B, (nb, *self.B.shape[1:])))
        return _sandwich(self.C, W)


class _Spring:
    def __init__(self, els):
        self.C, self.d = _affine([e.diff for e in els])
        self.k, self.l0, self.c = _values(els, "stiffness", "free_length", "damping")
        self.names = [e.name for e in els]

    def _args(self, Z):
        nb = Z.shape[0]
        d = _apply(self.C, self.d, Z)
        k, l0, c = (np.broadcast_to(x, (nb,)) if x.size == 1 else x
                    for x in (self.k, self.l0, self.c))
        return d, np.zeros_like(d), k, l0, c, lambda j: self.names[min(j, len(self.names) - 1)]

    def force(self, Z, Q):
        f = spring_forces(*self._args(Z))
        return -np.einsum("brm,br->bm", np.broadcast_to(self.C, (Z.shape[0], *self.C.shape[1:])),
                          f)

    def jacobians(self, Z, Q):
        Kf, Cf = spring_tangents(*self._args(Z))
        return _sandwich(self.C, Kf), _sandwich(self.C, Cf)


class _Torsional:
    def __init__(self, els):
        self.C, self.d = _affine([e.dirs for e in els])
        self.k, self.c, self.a0, self.sense = _values(els, "stiffness", "damping", "angle0",
                                                      "sense")
        self.names = [e.name for e in els]

    def _parts(self, Z):
        from ..errors import EquilibriumError

        v = _apply(self.C, self.d, Z)
        ax, ay, bx, by = v.T
        ra, rb = ax * ax + ay * ay, bx * bx + by * by
        bad = (ra == 0.0) | (rb == 0.0)
        if bad.any():
            raise EquilibriumError("direction of zero length: angle undefined",
                                   element=self.names[min(int(np.argmax(bad)),
                                                          len(self.names) - 1)])
        s = self.sense
        g = np.stack([ay / ra, -ax / ra, -by / rb, bx / rb], axis=1) * s[:, None]
        sa, sb = -s / (ra * ra), s / (rb * rb)
        pa, ma = 2 * ax * ay * sa, (ay * ay - ax * ax) * sa
        pb, mb = 2 * bx * by * sb, (by * by - bx * bx) * sb
        H = np.zeros((v.shape[0], 4, 4))
        H[:, 0, 0], H[:, 0, 1], H[:, 1, 0], H[:, 1, 1] = pa, ma, ma, -pa
        H[:, 2, 2], H[:, 2, 3], H[:, 3, 2], H[:, 3, 3] = pb, mb, mb, -pb
        theta = s * np.arctan2(ax * by - ay * bx, ax * bx + ay * by)
        dtheta = (theta - self.a0 + np.pi) % (2 * np.pi) - np.pi
        tau = self.k * dtheta  # (at rest: θ̇ = 0)
        return g, H, tau

    def force(self, Z, Q):
        g, _, tau = self._parts(Z)
        Ct = np.broadcast_to(np.swapaxes(self.C, 1, 2), (Z.shape[0], self.C.shape[2], 4))
        return -tau[:, None] * np.einsum("bmr,br->bm", Ct, g)

    def jacobians(self, Z, Q):
        g, H, tau = self._parts(Z)
        k = np.broadcast_to(self.k, tau.shape)
        c = np.broadcast_to(self.c, tau.shape)
        Kw = g[:, :, None] * (k[:, None] * g)[:, None, :] + tau[:, None, None] * H
        Cw = c[:, None, None] * (g[:, :, None] * g[:, None, :])
        return _sandwich(self.C, Kw), _sandwich(self.C, Cw)


class _Follower:
    def __init__(self, els):
        self.C, self.d = _affine([e.stacked for e in els])
        (self.f,) = _values(els, "magnitude")

    def force(self, Z, Q):
        u = _apply(self.C[:, 2:], self.d[:, 2:], Z)
        Cp = np.broadcast_to(self.C[:, :2], (Z.shape[0], 2, self.C.shape[2]))
        f = np.broadcast_to(self.f, (Z.shape[0],))
        return np.einsum("brm,br->bm", Cp, f[:, None] * u)

    def jacobians(self, Z, Q):
        nb, m = Z.shape[0], self.C.shape[2]
        f = np.broadcast_to(self.f, (nb,))
        K = -f[:, None, None] * (np.swapaxes(self.C[:, :2], 1, 2) @ self.C[:, 2:])
        return np.broadcast_to(K, (nb, m, m)), np.zeros((nb, m, m))


KERNELS = {DistanceConstraint: _Distance, LinearConstraint: _Linear,
           QuadraticConstraint: _Quadratic, SpringDamper: _Spring,
           TorsionalSpringDamper: _Torsional, FollowerForce: _Follower,
           WheelRows: _Quadratic}  # (a wheel's holonomic rows are quadratic rows, unchanged)


def _kernel(elements):
    first = elements[0]
    if all(e is first for e in elements):
        elements = [first]  # shared by every model: one member, broadcast over the batch
    cls = KERNELS.get(type(first))
    return (cls or _Each)(elements)


class ModelStack:
    """The B models ``models`` (one structure: :func:`stackable`) with their elements stacked
    (module docstring)."""

    def __init__(self, models):
        self.models = list(models)
        m0 = self.models[0]
        self.B, self.n, self.m = len(self.models), m0.n, m0.n_constraints
        self.forces = [(f.idx, _kernel([m.forces[k] for m in self.models]))
                       for k, f in enumerate(m0.forces)]
        off = np.cumsum([0] + [c.n_eq for c in m0.constraints])
        self.off = off
        self.constraints = [(c.idx, off[k], off[k + 1],
                             _kernel([m.constraints[k] for m in self.models]))
                            for k, c in enumerate(m0.constraints)]
        self.g_const = _stack([m.g_const for m in self.models])
        self.M = _stack([m.mass.toarray() for m in self.models])

    def _Z(self, Q, idx):
        return Q[:, idx]

    def take(self, idx):
        """The stack of the models ``idx`` (their rows of every stacked array; an array shared
        by all, of leading size 1, stays shared)."""
        idx = np.asarray(idx)
        out = copy.copy(self)
        B = self.B

        def part(ker):
            k = copy.copy(ker)
            for name, v in vars(ker).items():
                if isinstance(v, np.ndarray) and v.ndim and v.shape[0] == B and B > 1:
                    setattr(k, name, v[idx])
                elif isinstance(v, list) and len(v) == B and B > 1:
                    setattr(k, name, [v[i] for i in idx])
            return k

        out.models = [self.models[i] for i in idx]
        out.B = idx.size
        out.forces = [(i, part(k)) for i, k in self.forces]
        out.constraints = [(i, a, b, part(k)) for i, a, b, k in self.constraints]
        out.g_const = self.g_const[idx] if self.g_const.shape[0] == B and B > 1 else self.g_const
        out.M = self.M[idx] if self.M.shape[0] == B and B > 1 else self.M
        return out

    def g(self, Q):
        G = np.broadcast_to(self.g_const, Q.shape).copy()
        for idx, ker in self.forces:
            G[:, idx] += ker.force(self._Z(Q, idx), Q)
        return G

    def jacobians(self, Q):
        """(K, C) (B, n, n) at rest."""
        K = np.zeros((Q.shape[0], self.n, self.n))
        C = np.zeros_like(K)
        for idx, ker in self.forces:
            k, c = ker.jacobians(self._Z(Q, idx), Q)
            ix = np.ix_(idx, idx)
            K[:, ix[0], ix[1]] += k
            C[:, ix[0], ix[1]] += c
        return K, C

    def phi(self, Q):
        out = np.zeros((Q.shape[0], self.m))
        for idx, a, b, ker in self.constraints:
            out[:, a:b] = ker.phi(self._Z(Q, idx), Q)
        return out

    def phi_q(self, Q):
        out = np.zeros((Q.shape[0], self.m, self.n))
        for idx, a, b, ker in self.constraints:
            out[:, a:b, idx] += ker.jac(self._Z(Q, idx), Q)
        return out

    def hessian(self, Q, L):
        out = np.zeros((Q.shape[0], self.n, self.n))
        for idx, a, b, ker in self.constraints:
            ix = np.ix_(idx, idx)
            out[:, ix[0], ix[1]] += ker.hess(self._Z(Q, idx), Q, L[:, a:b])
        return out

    def projected_hessian(self, Q, L, N):
        """Nᵀ H(λ) N (B, d, d) for bases N (B, n, d), each element's block projected on its
        own coordinates (the dense H is never formed)."""
        out = np.zeros((Q.shape[0], N.shape[2], N.shape[2]))
        for idx, a, b, ker in self.constraints:
            if isinstance(ker, _Linear):
                continue  # (linear rows: no curvature)
            Ni = N[:, idx, :]
            out += np.swapaxes(Ni, 1, 2) @ ker.hess(self._Z(Q, idx), Q, L[:, a:b]) @ Ni
        return out
