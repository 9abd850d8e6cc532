"""Knife-edge rolling wheel on a plane, in natural coordinates, with the spin as a velocity.

An axisymmetric wheel (mass m, axial moment I_a about its axle a, transverse moment I_t about any
diameter, centre G on the axle) rolls without slip on the plane n·(r − p₀) = 0.  mbseig carries it
as a NON-SPINNING frame [r₀; u; v; w] (:mod:`mbseig.model.spatial_body`) plus one extra velocity,
the wheel's total angular rate about its axle

    Ω = ω·a        (ω: the wheel's angular velocity; the spin angle is never a coordinate)

The frame's own rotation about the axle is fixed by a gauge row: the body vector e_f that is
horizontal at the reference stays in the ground plane.  With the reference triad of the wheel

    e_d = (n − (n·a) a)/|…|   (in the wheel plane, towards the normal),   e_f = a × e_d

the gauge is n·e_f = 0, so n lies in span(a, e_d) and the lowest rim point is the FRAME point
C = G − R e_d (fixed in the frame although the material point at C changes all the time).

Rows (z = the 12 frame coordinates; every row is linear or bilinear):

    holonomic   Φ_c = n·(G − R e_d − p₀) / ℓ = 0      contact: the lowest rim point on the plane
                Φ_g = n·e_f = 0                        gauge of the non-spinning frame
    velocity    ψ_1 = e_f·Ġ − R Ω = 0                  no slip, forward
                ψ_2 = (n × e_f)·(Ġ − R ė_d) = 0        no slip, sideways

Derivation of ψ: the material point at C has velocity v_C = Ġ + ω × (−R e_d) with
ω = ω_f + σ a (ω_f the frame's rate, σ the spin relative to it, Ω = ω_f·a + σ).  Since
ω_f × e_d = ė_d, a × e_d = e_f and ω_f·a = e_f·ė_d,

    v_C = Ġ − R ė_d − R (Ω − e_f·ė_d) e_f,

whose e_f component is e_f·Ġ − RΩ (the e_f·ė_d terms cancel, e_f·e_f = 1), whose lateral
component (n × e_f ⊥ e_f) is (n × e_f)·(Ġ − R ė_d), and whose normal component is dΦ_c/dt·ℓ
(n·e_f = 0).  So the three no-slip conditions are exactly Φ̇_c = 0, ψ_1 = 0, ψ_2 = 0.

Each velocity row is ψ_k = (X_k z)·(Y_k ż) + b_k Ω with constant X_k, Y_k, b = (−R, 0), so

    A_k(q) = (X_k z)ᵀ Y_k C,    ∂(A_k(q) q̇)/∂q = (Y_k ż)ᵀ X_k C,
    ∂(A_k(q)ᵀ μ_k)/∂q = μ_k Cᵀ Y_kᵀ X_k C

exactly (z = C q + d the frame map of the wheel body).

Dynamics of the spin.  The wheel's angular momentum is H = I_t ω⊥ + I_a Ω a (ω⊥ the part of ω
normal to a, the same for the wheel and its frame).  The frame carries the wheel's mass and the
transverse inertia only (inertia I − I_a a aᵀ: :meth:`RollingWheel.mass_correction` removes the
axial part from the body's mass matrix), and

    I_a Ω̇ = a·(moments on the wheel)  = −b·μ           (the spin's own equation)
    frame:  gyroscopic moment T = −I_a Ω ȧ               (:meth:`RollingWheel.gyroscopic`)

by splitting dH/dt = d(I_t ω⊥)/dt + I_a Ω̇ a + I_a Ω ȧ along a and normal to it (both
d(I_t ω⊥)/dt and ȧ are normal to a).  T is mbseig's ``rotor`` moment with a variable speed Ω.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from .affine import Affine
from .base import VelocityConstraint
from .spatial_body import point_matrix, second_moment, vector_matrix
from .spatial_forces import moment_force, skew
from .spatial_joints import QuadraticConstraint, Rows

__all__ = ["Motion", "RollingWheel", "WheelRows", "rolling_wheel", "wheel_problem", "wheels_of"]


@dataclass(frozen=True)
class Motion:
    """The reference of a steady motion (DESIGN §8 ``[motion]``): speed v along the unit
    ``direction``; ``yaw_rate`` about the gravity axis."""

    speed: float
    direction: tuple = (1.0, 0.0, 0.0)
    yaw_rate: float = 0.0
    up: tuple = (0.0, 0.0, 1.0)  # the gravity axis (against gravity)


@dataclass(frozen=True, eq=False)
class WheelRows(QuadraticConstraint):
    """The holonomic rows of a rolling wheel (contact height / ℓ, gauge) as a model constraint;
    ``wheel`` is the :class:`RollingWheel` whose velocity rows go with them.  The contact row
    is single-sided in a steady motion (its normal force is reported and checked there); the
    static contact solve does not release it (a wheel is analysed in a ``[motion]`` only)."""

    wheel: object = None


def wheels_of(model) -> tuple:
    """The rolling wheels of ``model``: its velocity constraints, or the wheels carried by its
    :class:`WheelRows` constraints (the reader places the rows among the constraints)."""
    found = tuple(v for v in getattr(model, "velocity_constraints", ())
                  if isinstance(v, RollingWheel))
    if found:
        return found
    return tuple(c.wheel for c in model.constraints if isinstance(c, WheelRows))


def _unit(x):
    x = np.asarray(x, float)
    return x / np.linalg.norm(x)


def wheel_problem(inertia, axis, *, rtol=1e-9):
    """Why a body with ``inertia`` (3×3 about its centre of mass, global axes at the reference)
    cannot roll as an axisymmetric wheel about ``axis``, or None: ``axis`` must be a principal
    axis and the two moments normal to it must be equal."""
    inertia = np.asarray(inertia, float)
    a = np.asarray(axis, float)
    if not np.isfinite(a).all() or np.linalg.norm(a) == 0:
        return "axis must be a non-zero vector"
    a = a / np.linalg.norm(a)
    scale = max(float(np.abs(inertia).max()), 1e-300)
    Ia = a @ inertia @ a
    if np.linalg.norm(inertia @ a - Ia * a) > rtol * scale:
        return "the wheel is not axisymmetric about its axle (axis is not a principal axis)"
    p = np.linalg.svd(a.reshape(1, 3))[2][1:]  # two unit vectors normal to a
    It = p @ inertia @ p.T
    if abs(It[0, 0] - It[1, 1]) > rtol * scale or abs(It[0, 1]) > rtol * scale:
        return (f"the wheel is not axisymmetric about its axle (moments normal to it "
                f"{It[0, 0]:.6g}, {It[1, 1]:.6g})")
    return None


@dataclass(frozen=True, eq=False)
class RollingWheel(VelocityConstraint):
    """A knife-edge wheel on a plane (module docstring for the rows and their derivatives).

    frame : the 12-row map z = C q[idx] + d of the wheel body.
    centre : local coordinates ξ_G of the wheel centre (= its centre of mass) in the body frame.
    axis, e_d, e_f : reference (= local) components of the axle, the in-plane direction towards
        the normal and the forward direction a × e_d.
    radius, normal, plane_point : R, unit n, p₀.  axial_inertia : I_a.  length : ℓ of the
        holonomic contact row (mbseig divides position rows by the model's length).
    """

    name: str
    frame: Affine
    centre: np.ndarray
    axis: np.ndarray
    e_d: np.ndarray
    e_f: np.ndarray
    radius: float
    normal: np.ndarray
    plane_point: np.ndarray
    axial_inertia: float
    length: float = 1.0

    n_holonomic = 2
    n_velocity = 2
    n_eq = 2
    affine_field = "frame"

    def rows(self, q):
        """A(q) of the element contract (:class:`~mbseig.model.base.VelocityConstraint`)."""
        return self.velocity_jacobian(q)

    def rows_q(self, q, qd):
        """∂(A(q) q̇)/∂q at q̇ (the element contract)."""
        return self.velocity_jacobian_q(q, qd)

    # ---- the holonomic rows: contact and gauge (both linear in z) ---------------------------
    def holonomic(self) -> WheelRows:
        """Φ_c (contact height / ℓ) and Φ_g (gauge) as an mbseig constraint on the frame."""
        n, R = self.normal, self.radius
        Pc = point_matrix(self.centre) - R * vector_matrix(self.e_d)
        rows = Rows(self.frame)
        rows.linear(n @ Pc / self.length, -(n @ self.plane_point) / self.length)
        rows.linear(n @ vector_matrix(self.e_f))
        return WheelRows(f"{self.name} (contact, gauge)", rows.build(), self.length, None,
                         wheel=self)

    # ---- the velocity rows ---------------------------------------------------------------------
    @cached_property
    def _xy(self):
        """(X_k, Y_k) of ψ_k = (X_k z)·(Y_k ż) + b_k Ω (constant: computed once)."""
        Vf = vector_matrix(self.e_f)
        Pg = point_matrix(self.centre)
        Vd = vector_matrix(self.e_d)
        return ((Vf, Pg), (skew(self.normal) @ Vf, Pg - self.radius * Vd))

    @property
    def spin_column(self) -> np.ndarray:
        """b = ∂ψ/∂Ω (2,)."""
        return np.array([-self.radius, 0.0])

    def velocity_rows(self, q, qd, spin):
        """ψ(q, q̇, Ω) (2,): the tangential velocity of the material contact point."""
        z, zd = self.frame(q), self.frame.rate(qd)
        return np.array([(X @ z) @ (Y @ zd) for X, Y in self._xy]) + self.spin_column * spin

    def velocity_jacobian(self, q):
        """A(q) = ∂ψ/∂q̇ (2 × len(idx)); ψ = A(q) q̇ + b Ω."""
        z, C = self.frame(q), self.frame.C
        return np.array([(X @ z) @ Y @ C for X, Y in self._xy])

    def velocity_jacobian_q(self, q, qd):
        """∂(A(q) q̇)/∂q at the velocities q̇ (2 × len(idx)): the term a linearization about a
        moving reference must keep."""
        zd, C = self.frame.rate(qd), self.frame.C
        return np.array([(Y @ zd) @ X @ C for X, Y in self._xy])

    def multiplier_stiffness(self, mu):
        """∂(A(q)ᵀ μ)/∂q (len(idx) square, constant): Σ_k μ_k Cᵀ Y_kᵀ X_k C."""
        C = self.frame.C
        return sum(m * C.T @ Y.T @ X @ C for m, (X, Y) in zip(mu, self._xy, strict=True))

    # ---- mass and the gyroscopic moment of the spin -----------------------------------------
    def mass_correction(self):
        """ΔM on idx: minus the axial inertia I_a a aᵀ, so the body's mass matrix becomes that
        of the non-spinning frame (mass and transverse inertia only)."""
        A = np.zeros((4, 4))
        A[1:, 1:] = second_moment(self.axial_inertia * np.outer(self.axis, self.axis))
        C = self.frame.C
        return -C.T @ np.kron(A, np.eye(3)) @ C

    def gyroscopic(self, q, qd, spin):
        """(g, ∂g/∂q, ∂g/∂q̇, ∂g/∂Ω) of the moment T = −I_a Ω ȧ on the frame (on idx)."""
        C = self.frame.C
        Va = vector_matrix(self.axis)
        ad = Va @ self.frame.rate(qd)
        T = -self.axial_inertia * spin * ad
        g, dz, dT = moment_force(self.frame(q), T)
        return (C.T @ g, C.T @ dz @ C, C.T @ dT @ (-self.axial_inertia * spin * Va) @ C,
                C.T @ dT @ (-self.axial_inertia * ad))


def rolling_wheel(name, frame, *, origin, com, inertia, axis, radius, normal=(0.0, 0.0, 1.0),
                  plane_point=(0.0, 0.0, 0.0), length=1.0, atol=1e-9):
    """A :class:`RollingWheel` for a body with reference ``origin`` (its basic point), centre of
    mass ``com`` (the wheel centre) and ``inertia`` (global axes at the reference).  Raises
    ValueError with a one-line reason for a wheel that is not axisymmetric, an axle along the
    normal, a zero normal or a wheel that does not touch the plane at the reference."""
    normal = np.asarray(normal, float)
    if not np.isfinite(normal).all() or np.linalg.norm(normal) == 0:
        raise ValueError("normal must be a non-zero vector")
    if not radius > 0:
        raise ValueError(f"radius must be positive (got {radius})")
    problem = wheel_problem(inertia, axis)
    if problem:
        raise ValueError(problem)
    n, a = _unit(normal), _unit(axis)
    ed = n - (n @ a) * a
    if np.linalg.norm(ed) < 1e-6:
        raise ValueError("the axle is normal to the ground plane: the wheel lies flat")
    ed = _unit(ed)
    ef = np.cross(a, ed)
    com, p0 = np.asarray(com, float), np.asarray(plane_point, float)
    gap = n @ (com - radius * ed - p0)
    if abs(gap) > atol * max(1.0, radius):
        raise ValueError(f"the wheel does not touch the plane at the reference (gap {gap:.6g})")
    Ia = float(a @ np.asarray(inertia, float) @ a)
    return RollingWheel(name, frame, com - np.asarray(origin, float), a, ed, ef, float(radius), n,
                        p0, Ia, float(length))
