"""Spatial force elements on body frames [r₀; u; v; w] (:mod:`mbseig.model.spatial_body`).

Sign conventions as everywhere (docs/design.md, "Elements"): g is the generalized force,
K = −∂g/∂q, C = −∂g/∂q̇.

A moment T on a body is the generalized force (virtual work δθ·T with δe = δθ × e)

    g_r = 0,   g_e = ½ T × e   (e = u, v, w),   since Σ_e e × (½ T × e) = ½ (3T − Σ_e e (e·T)) = T

for an orthonormal triad; :func:`moment_force` evaluates it and its derivatives.  On it rest

- :class:`BodyMoment`: a torque fixed in space or following the body (T = body vector);
- :class:`Rotor`: an axisymmetric rotor of polar inertia J_p spinning at Ω about the body axis a:
  the body feels the gyroscopic moment T = −J_p Ω ȧ, linear in q̇, so C = −∂g/∂q̇ ∝ Ω and, on the
  constraint manifold, Nᵀ C N is skew (the moment does no work: Σ_e ė·(e × ȧ) = −2 ω·ȧ = 0);
- :class:`PointFollowerForce`: a force at a body point along a body vector (non-conservative);
- :class:`QuadraticSpringDamper`: a linear spring-damper law f = K e + D ė on quadratic
  generalized strains e(q) (:class:`~mbseig.model.spatial_joints.QuadraticMap`): the bushing,
  whose strains are the displacement of b2's point relative to b1's in b1's axes and the small
  rotation vector θ = ½ (w₁·v₂ − v₁·w₂, u₁·w₂ − w₁·u₂, v₁·u₂ − u₁·v₂) (exact to second order,
  zero at the reference):  g = −Cᵀ Gᵀ f,  K = Cᵀ [Gᵀ (K G + D Ġ) + Σ f_i ∇²e_i] C,
  C = Cᵀ Gᵀ D G C with G = ∂e/∂z and Ġ_i = 2 B_i ż;
- :class:`SpatialTorsional`: a torsional spring-damper about a revolute axis (the planar law on
  the angle of :func:`~mbseig.model.spatial_joints.axis_angle`).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from .affine import Affine, combine
from .base import Force
from .elements import TorsionalSpringDamper
from .spatial_body import FRAME_SIZE, point_matrices, point_matrix, vector_matrix
from .spatial_joints import QuadraticMap, Rows, axis_angle, selectors

__all__ = [
    "BodyMoment",
    "PointFollowerForce",
    "QuadraticSpringDamper",
    "Rotor",
    "SpatialTorsional",
    "bushing_maps",
    "bushing_rows",
    "moment_force",
    "skew",
]


def skew(a):
    """[a]ₓ with [a]ₓ b = a × b."""
    return np.array([[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]], dtype=a.dtype)


def moment_force(frame_z, T):
    """(g, ∂g/∂frame, ∂g/∂T): g_e = ½ T × e on a frame z = [r₀; u; v; w] (12,), module docstring."""
    e = frame_z.reshape(4, 3)
    g = np.zeros(FRAME_SIZE, dtype=np.result_type(frame_z, T))
    dz = np.zeros((FRAME_SIZE, FRAME_SIZE), dtype=g.dtype)
    dT = np.zeros((FRAME_SIZE, 3), dtype=g.dtype)
    ST = skew(T)
    for k in range(1, 4):
        rows = slice(3 * k, 3 * k + 3)
        g[rows] = 0.5 * (ST @ e[k])
        dz[rows, rows] = 0.5 * ST
        dT[rows] = -0.5 * skew(e[k])
    return g, dz, dT


@dataclass(frozen=True, eq=False)
class BodyMoment(Force):
    """Torque on a body: ``stacked`` = [frame (12 rows); T (3 rows)], T constant (fixed in space)
    or a body vector (``follower``)."""

    name: str
    stacked: Affine
    affine_field = "stacked"

    def force(self, q, qd):
        z = self.stacked(q)
        C = self.stacked.C
        return C[:FRAME_SIZE].T @ moment_force(z[:FRAME_SIZE], z[FRAME_SIZE:])[0]

    def jacobians(self, q, qd):
        z = self.stacked(q)
        C = self.stacked.C
        _, dz, dT = moment_force(z[:FRAME_SIZE], z[FRAME_SIZE:])
        K = -C[:FRAME_SIZE].T @ (dz @ C[:FRAME_SIZE] + dT @ C[FRAME_SIZE:])
        return K, np.zeros_like(K)


@dataclass(frozen=True, eq=False)
class Rotor(Force):
    """Axisymmetric rotor (polar inertia J_p, spin Ω about the body axis with local components
    ``axis``) carried by a body frame: gyroscopic moment T = −J_p Ω ȧ (module docstring).

    ``body`` names the carrier; ``stations`` are (label, Affine) of the points whose orbits
    define the whirl of a mode (:func:`mbseig.model.spatial_whirl.whirl`).
    """

    glyph = "rotor"
    station_map = None  # a rigid rotor: its stations read one at a time (a SpinningShaft has one)

    name: str
    frame: Affine
    axis: np.ndarray
    polar_inertia: float
    speed: float
    body: str = ""
    stations: tuple = ()
    affine_field = "frame"

    def _gain(self):
        return self.polar_inertia * self.speed

    def axis_map(self) -> Affine:
        """The spin axis a(q) as a linear map of the frame."""
        V = vector_matrix(self.axis)
        return Affine(self.frame.idx, V @ self.frame.C, V @ self.frame.d)

    def force(self, q, qd):
        C = self.frame.C
        a_dot = vector_matrix(self.axis) @ (C @ qd[self.idx])
        return C.T @ moment_force(self.frame(q), -self._gain() * a_dot)[0]

    def jacobians(self, q, qd):
        C = self.frame.C
        Va = vector_matrix(self.axis)
        T = -self._gain() * (Va @ (C @ qd[self.idx]))
        _, dz, dT = moment_force(self.frame(q), T)
        return -C.T @ dz @ C, C.T @ dT @ (self._gain() * Va) @ C


@dataclass(frozen=True, eq=False)
class PointFollowerForce(Force):
    """Force F(q) (a body vector, or any linear map) at a point: ``stacked`` = [r_P; F] (6 rows).
    g = C_Pᵀ F,  K = −C_Pᵀ C_F (not symmetric)."""

    name: str
    stacked: Affine
    affine_field = "stacked"

    def force(self, q, qd):
        return self.stacked.C[:3].T @ self.stacked(q)[3:]

    def jacobians(self, q, qd):
        C = self.stacked.C
        K = -C[:3].T @ C[3:]
        return K, np.zeros_like(K)


@dataclass(frozen=True, eq=False)
class QuadraticSpringDamper(Force):
    """f = K e + D ė on the strains e of a :class:`QuadraticMap` (module docstring); the strain
    energy ½ eᵀKe is zero where e = 0 (a bushing: at the reference)."""

    name: str
    rows: QuadraticMap
    stiffness: np.ndarray
    damping: np.ndarray
    # many at once: mbseig.model.batched.QuadraticGroup (this class only)
    kernel = "quadratic strains"
    affine_field = "aff"

    @property
    def aff(self):
        return self.rows.aff

    def _state(self, q, qd):
        z, zd = self.aff(q), self.aff.rate(qd)
        G = self.rows.grad(z)
        f = self.stiffness @ self.rows.values(z) + self.damping @ (G @ zd)
        return z, zd, G, f

    def strains(self, q):
        return self.rows.values(self.aff(q))

    def force(self, q, qd):
        _, _, G, f = self._state(q, qd)
        return -(self.aff.C.T @ (G.T @ f))

    def jacobians(self, q, qd):
        _, zd, G, f = self._state(q, qd)
        C = self.aff.C
        Gdot = 2.0 * (self.rows.B @ zd)
        Kz = G.T @ (self.stiffness @ G + self.damping @ Gdot) + self.rows.weighted(f)
        return C.T @ Kz @ C, C.T @ (G.T @ self.damping @ G) @ C


def bushing_rows(frames, locals_) -> QuadraticMap:
    """Strains of a bushing at a point: d = R₁ᵀ(P₂ − P₁) and the small rotation of b2 relative
    to b1 in b1's axes (module docstring), on the stacked frames."""
    z = combine([(1.0, frames[0]), (1.0, frames[1])], stack=True)
    S1, S2, E1, rotation = _bushing_constants()
    rows = Rows(z)
    D = point_matrix(locals_[1]) @ S2 - point_matrix(locals_[0]) @ S1
    for k in range(3):
        rows.dot(E1[k], D)
    for B in rotation:
        rows.B.append(B)
        rows.b.append(np.zeros(rows.p))
        rows.c.append(0.0)
    return rows.build()


def bushing_maps(stacks, locals0, locals1) -> list:
    """:func:`bushing_rows` of many bushings at once: ``stacks`` their stacked frame maps,
    ``locals0``, ``locals1`` (nb, 3) the point in each frame.  The same rows (the strain forms
    are sums of single products of selector entries, exact in any order: no value changes)."""
    S1, S2, E1, rotation = _bushing_constants()
    D = point_matrices(locals1) @ S2 - point_matrices(locals0) @ S1  # (nb, 3, 24)
    B = np.empty((len(stacks), 6, 2 * FRAME_SIZE, 2 * FRAME_SIZE))
    T = np.empty((len(stacks), 2 * FRAME_SIZE, 2 * FRAME_SIZE))
    for k in range(3):  # Eₖᵀ D places D's rows at the components of b1's axis k (a selector)
        T[:] = 0.0
        T[:, np.argmax(E1[k], axis=1), :] = D
        B[:, k] = 0.5 * (T + T.transpose(0, 2, 1))
    B[:, 3:] = rotation
    return [QuadraticMap(z, B[n], np.zeros((6, 2 * FRAME_SIZE)), np.zeros(6))
            for n, z in enumerate(stacks)]


@functools.lru_cache(maxsize=1)
def _bushing_constants():
    """(S1, S2, E1, rotation rows) of every bushing on stacked frames: the frame selectors, b1's
    axes e_k = E1[k] z, and the quadratic forms of the small rotation θ_x = ½(w₁·v₂ − v₁·w₂),
    cyclic (the same for every bushing: made once, read-only)."""
    S1, S2 = selectors()
    E1 = [vector_matrix(e) @ S1 for e in np.eye(3)]
    E2 = [vector_matrix(e) @ S2 for e in np.eye(3)]
    rotation = []
    for i, j in ((2, 1), (0, 2), (1, 0)):
        X = 0.5 * (E1[i].T @ E2[j] - E1[j].T @ E2[i])
        rotation.append(0.5 * (X + X.T))
    for A in (S1, S2, *E1, *rotation):
        A.setflags(write=False)
    return S1, S2, tuple(E1), tuple(rotation)


@dataclass(frozen=True, eq=False)
class SpatialTorsional(TorsionalSpringDamper):
    """Torsional spring-damper about a revolute axis: τ = k wrap(θ − θ₀) + c θ̇ resists the
    rotation θ of b2 relative to b1 (:func:`~mbseig.model.spatial_joints.axis_angle`); ``dirs``
    is the map of the two frames, ``rows`` the two rows of the angle.  Force and Jacobians are
    the planar element's law on that angle."""

    rows: QuadraticMap | None = None

    def angle(self, q):
        return float(axis_angle(self.rows, self.dirs(q))[0].real)

    def torque_parts(self, q, qd):
        W = self.dirs.C
        theta, g, H = axis_angle(self.rows, self.dirs(q))
        wd = W @ qd[self.idx]
        wrapped = (theta - self.angle0 + math.pi) % (2 * math.pi) - math.pi
        return W, g, H, wd, self.stiffness * wrapped + self.damping * (g @ wd)
