"""Spatial constraints: rigid-body conditions and joints as quadratic forms of body frames.

Every spatial constraint of mbseig is a set of rows

    Φ_k(q) = zᵀ B_k z + b_k · z + c_k,      z = C q[idx] + d

on the stacked frames z = [r₀; u; v; w] of the bodies it joins (:mod:`mbseig.model.spatial_body`;
"ground" is a constant frame).  Coincident points are linear rows, "this body vector is normal to
that one" and "this point lies on that body's line or plane" are dot products (bilinear rows),
unit vectors are squares.  So (docs/design.md, "Elements")

    Φ_q = (2 B_k z + b_k)ᵀ C,   Σ λ_k ∇²Φ_k = 2 Cᵀ (Σ λ_k B_k) C,   γ_k = −2 żᵀ B_k ż

exactly: the constraint-force stiffness needs no approximation.  Position rows are divided by the
model's length ℓ so that every row is dimensionless (one residual scale per element); the
reactions are computed from −Φ_qᵀλ and are independent of that choice.

Joints (``bodies = [b1, b2]``, point ``at``; p, q̂ complete the axis a to an orthonormal basis):

=================  ========================================================  ====
spherical          P₁(at) = P₂(at)                                              3
revolute (a)       spherical, a₁·p₂ = 0, a₁·q̂₂ = 0                              5
universal (a1,a2)  spherical, a1₁·a2₂ = 0                                       4
cylindrical (a)    a₁·p₂ = a₁·q̂₂ = 0, (P₁ − P₂)·p₂ = (P₁ − P₂)·q̂₂ = 0            4
prismatic (a)      cylindrical, p₁·q̂₂ = 0                                       5
weld               spherical, x₁·y₂ = y₁·z₂ = z₁·x₂ = 0                          6
point_on_line (a)  (P₁ − P₂)·p₂ = (P₁ − P₂)·q̂₂ = 0   (line fixed in b2)          2
point_on_plane (n) (P₁ − P₂)·n₂ = 0                  (plane fixed in b2)         1
=================  ========================================================  ====

The relative angle about a revolute axis, θ = atan2(q̂₁·p₂, p₁·p₂) (right-handed about a, b2
relative to b1, zero at the reference), is a function of two bilinear rows; the angle driver and
the torsional spring use it (:func:`axis_angle`).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, field

import numpy as np

from .affine import Affine, combine, shared_constant
from .base import Constraint
from .driver import AngleDriver
from .elements import angle_derivatives
from .spatial_body import FRAME_SIZE, point_matrix, vector_matrix

__all__ = [
    "JOINT_ROWS",
    "QuadraticConstraint",
    "QuadraticMap",
    "Rows",
    "SpatialAngleDriver",
    "angle_rows",
    "axis_angle",
    "frame_wrench",
    "joint_rows",
    "normal_pair",
    "triad_constraint",
]

#: equations per joint type
JOINT_ROWS = {"spherical": 3, "revolute": 5, "universal": 4, "cylindrical": 4, "prismatic": 5,
              "weld": 6, "point_on_line": 2, "point_on_plane": 1, "planar": 3}


@dataclass(frozen=True, eq=False)
class QuadraticMap:
    """e_k = zᵀ B_k z + b_k·z + c_k with z = aff(q); B_k symmetric (k, p, p)."""

    aff: Affine
    B: np.ndarray
    b: np.ndarray
    c: np.ndarray

    def values(self, z):
        return np.einsum("kij,i,j->k", self.B, z, z) + self.b @ z + self.c

    def grad(self, z):
        """∂e/∂z (k, p)."""
        return 2.0 * (self.B @ z) + self.b

    def weighted(self, w):
        """Σ_k w_k ∇²e_k with respect to z: 2 Σ_k w_k B_k."""
        return 2.0 * np.tensordot(w, self.B, axes=1)


class Rows:
    """Collects rows of a :class:`QuadraticMap` on z (p components): linear rows L z and dot
    products (X z)·(Y z), X, Y, L constant matrices on z."""

    def __init__(self, aff: Affine):
        self.aff, self.p = aff, aff.C.shape[0]
        self.B, self.b, self.c = [], [], []

    def linear(self, L, const=None):
        L = np.atleast_2d(L)
        for k in range(L.shape[0]):
            self.B.append(np.zeros((self.p, self.p)))
            self.b.append(L[k])
            self.c.append(0.0 if const is None else float(np.atleast_1d(const)[k]))
        return self

    def dot(self, X, Y, const=0.0):
        self.B.append(0.5 * (X.T @ Y + Y.T @ X))
        self.b.append(np.zeros(self.p))
        self.c.append(float(const))
        return self

    def build(self) -> QuadraticMap:
        # (equal quadratics of many joints stored once: affine.shared_constant)
        return QuadraticMap(self.aff, shared_constant(np.array(self.B)), np.array(self.b),
                            np.array(self.c))


def frame_wrench(z_frame, f_frame, point_local):
    """(F, M_P): resultant force and moment about the body point ξ of generalized forces
    f = [f_r; f_u; f_v; f_w] on a frame z = [r₀; u; v; w].  Virtual work: f_r·δr₀ + Σ f_e·(δθ × e)
    = F·δr₀ + δθ·Σ e × f_e, so F = f_r, M₀ = Σ e × f_e and M_P = M₀ + (r₀ − r_P) × F."""
    e = z_frame.reshape(4, 3)
    f = f_frame.reshape(4, 3)
    F = f[0]
    M0 = np.cross(e[1:], f[1:]).sum(axis=0)
    rP = point_matrix(point_local) @ z_frame
    return F, M0 + np.cross(e[0] - rP, F)


@dataclass(frozen=True, eq=False)
class QuadraticConstraint(Constraint):
    """Rows Φ = e(q) of a :class:`QuadraticMap` (module docstring).

    wrench : None, or (offset of a body's frame in z, local coordinates of the joint point on it,
        body name): the reaction is then the force and moment the constraint exerts on that body
        about the joint point; otherwise the multipliers.
    """

    name: str
    rows: QuadraticMap
    residual_scale: float = 1.0
    wrench: tuple | None = None
    # ("triad", BODY or None): a frame's rigid-body conditions (reactions); keyword-only, so the
    # positional fields of the subclasses (contacts, wheels) follow ``wrench`` as before
    role: tuple = field(default=(), kw_only=True)
    kernel = "quadratic rows"  # many at once: mbseig.model.batched.QuadraticGroup (this class only)
    affine_field = "aff"

    @property
    def aff(self):
        return self.rows.aff

    @property
    def n_eq(self):
        return self.rows.c.size

    def phi(self, q):
        return self.rows.values(self.aff(q))

    def jac(self, q):
        return self.rows.grad(self.aff(q)) @ self.aff.C

    def hess(self, q, lam):
        C = self.aff.C
        return C.T @ self.rows.weighted(lam) @ C

    def gamma(self, q, qd):
        zd = self.aff.rate(qd)
        return -2.0 * np.einsum("kij,i,j->k", self.rows.B, zd, zd)

    def scale(self):
        return self.residual_scale

    def reaction(self, q, lam):
        """Force [N] and moment [N m] (about the joint point) on the joint's body."""
        if self.wrench is None:
            return super().reaction(q, lam)
        off, local, body = self.wrench
        z = self.aff(q)
        f = -(self.rows.grad(z).T @ lam)
        F, M = frame_wrench(z[off:off + FRAME_SIZE], f[off:off + FRAME_SIZE], local)
        return {"key": "wrench", "label": f"force, moment on {body}",
                "value": [float(x) + 0.0 for x in np.concatenate([F, M])], "unit": "N, N m"}


def triad_constraint(name: str, frame: Affine, body: str | None = None) -> QuadraticConstraint:
    """The six rigid-body conditions of a frame: u·u = v·v = w·w = 1, u·v = v·w = w·u = 0
    (``body``: the spatial body whose frame it is; None for a beam node's triad)."""
    B, b, c = _triad_constants()
    return QuadraticConstraint(name, QuadraticMap(frame, B, b, c), role=("triad", body))


@functools.lru_cache(maxsize=1)
def _triad_constants():
    """(B, b, c) of the six rigid-body conditions on a frame (the same for every body: made
    once, read-only, shared by the bodies' constraints)."""
    rows = Rows(Affine.constant(np.zeros(FRAME_SIZE)))
    E = [vector_matrix(e) for e in np.eye(3)]
    for a, b, const in ((0, 0, -1.0), (1, 1, -1.0), (2, 2, -1.0), (0, 1, 0.0), (1, 2, 0.0),
                        (2, 0, 0.0)):
        rows.dot(E[a], E[b], const)
    built = rows.build()
    for A in (built.B, built.b, built.c):
        A.setflags(write=False)
    return built.B, built.b, built.c


def normal_pair(a):
    """Two unit vectors p, q̂ with (p, q̂, a) right-handed and orthonormal (a a unit vector)."""
    a = np.asarray(a, float)
    t = np.eye(3)[int(np.argmin(np.abs(a)))]
    p = np.cross(t, a)
    p /= np.linalg.norm(p)
    return p, np.cross(a, p)


@functools.lru_cache(maxsize=1)
def selectors():
    """(S1, S2): the first and the second frame of two stacked frames (made once, read-only)."""
    S1 = np.hstack([np.eye(FRAME_SIZE), np.zeros((FRAME_SIZE, FRAME_SIZE))])
    S2 = np.roll(S1, FRAME_SIZE, axis=1)
    for A in (S1, S2):
        A.setflags(write=False)
    return S1, S2


def joint_rows(kind: str, frames, locals_, axes, length: float) -> QuadraticMap:
    """The rows of a joint of type ``kind`` (module table) between two frames.

    frames : (frame₁, frame₂) 12-row maps (a constant one for ground); locals_ : the joint point
    in each body's local coordinates; axes : the reference-global unit vectors the type needs
    (``axis``; for universal the two axes; for point_on_plane the normal); length : ℓ, the divisor
    of position rows.
    """
    z = combine([(1.0, frames[0]), (1.0, frames[1])], stack=True)
    S1, S2 = selectors()
    rows = Rows(z)
    P = (point_matrix(locals_[0]) @ S1 - point_matrix(locals_[1]) @ S2) / length

    def V1(e):
        return vector_matrix(e) @ S1

    def V2(e):
        return vector_matrix(e) @ S2

    if kind in ("spherical", "revolute", "universal", "weld"):
        rows.linear(P)
    if kind in ("revolute", "cylindrical", "prismatic"):
        a = axes[0]
        p, qn = normal_pair(a)
        rows.dot(V1(a), V2(p)).dot(V1(a), V2(qn))
        if kind != "revolute":
            rows.dot(P, V2(p)).dot(P, V2(qn))
        if kind == "prismatic":
            rows.dot(V1(p), V2(qn))
    elif kind == "universal":
        rows.dot(V1(axes[0]), V2(axes[1]))
    elif kind == "weld":
        ex, ey, ez = np.eye(3)
        rows.dot(V1(ex), V2(ey)).dot(V1(ey), V2(ez)).dot(V1(ez), V2(ex))
    elif kind == "point_on_line":
        p, qn = normal_pair(axes[0])
        rows.dot(P, V2(p)).dot(P, V2(qn))
    elif kind == "point_on_plane":
        rows.dot(P, V2(axes[0]))
    elif kind == "planar":  # b2 slides in the plane normal to its axis and turns about it
        p, qn = normal_pair(axes[0])
        rows.dot(V1(axes[0]), V2(p)).dot(V1(axes[0]), V2(qn)).dot(P, V2(axes[0]))
    return rows.build()


# ---------------------------------------------------------------------------------------------
# The relative angle about a revolute axis
# ---------------------------------------------------------------------------------------------
def angle_rows(frames, axis) -> QuadraticMap:
    """x = p₁·p₂ and y = q̂₁·p₂ on the two frames: θ = atan2(y, x) is the rotation of b2
    relative to b1 about ``axis`` (right-handed), zero at the reference."""
    z = combine([(1.0, frames[0]), (1.0, frames[1])], stack=True)
    S1, S2 = selectors()
    p, qn = normal_pair(axis)
    p2 = vector_matrix(p) @ S2
    return (Rows(z).dot(vector_matrix(p) @ S1, p2).dot(vector_matrix(qn) @ S1, p2)).build()


def axis_angle(rows: QuadraticMap, z):
    """(θ, ∇θ, ∇²θ) with respect to z of θ = atan2(y, x), (x, y) the two rows of ``rows``."""
    xy = rows.values(z)
    G = rows.grad(z)
    gv, Hv = angle_derivatives(xy)
    theta = np.arctan2(xy[1], xy[0])
    return theta, gv @ G, G.T @ Hv @ G + rows.weighted(gv)


@dataclass(frozen=True, eq=False)
class SpatialAngleDriver(AngleDriver):
    """Φ = wrap(θ(q) − θ*) about a revolute axis (θ of :func:`axis_angle`); ``dirs`` is the map
    of the two frames.  Phi wrapping, Jacobian, Hessian, γ and the reaction (the torque −λ
    that holds the angle) are those of the planar :class:`~mbseig.model.driver.AngleDriver`."""

    rows: QuadraticMap | None = None

    def angle(self, q) -> float:
        return float(axis_angle(self.rows, self.dirs(q))[0].real)

    def _derivatives(self, q):
        _, g, H = axis_angle(self.rows, self.dirs(q))
        return g, H
