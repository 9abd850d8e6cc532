"""Planar beams: co-rotational Euler–Bernoulli and Timoshenko elements in natural coordinates.

A beam node is a basic point (x, y) plus one angle coordinate θ, the absolute angle of the
cross-section's tangent direction.  An element between nodes 1 and 2 acts on

    w = [x₁, y₁, θ₁, x₂, y₂, θ₂] = C q[idx] + d          (an :class:`~mbseig.model.affine.Affine`)

so that fixed points and clamped angles are constants, like every other element.

Kinematics (co-rotational, Crisfield 1991 §7; shallow-arch local strain):

    d = r₂ − r₁,  l = |d|,  β = atan2(d_y, d_x),   u = l − l₀,   φᵢ = θᵢ − β   (wrapped)
    ε̄ = u/l₀ + ½ φᵀ G φ,      G = (1/l₀) ∫₀^l₀ N_φ′ N_φ′ᵀ dx   (average axial strain)
    U = ½ EA l₀ ε̄² + ½ φᵀ K_b φ

K_b is the bending stiffness on the rotations relative to the chord: Euler–Bernoulli
EI/l₀ [[4, 2], [2, 4]], Timoshenko (interdependent interpolation, Φ = 12 EI/(κ G A l₀²))

    K_b = EI / (l₀ (1 + Φ)) [[4 + Φ, 2 − Φ], [2 − Φ, 4 + Φ]].

The quadratic ½ φᵀGφ term makes the axial force N = EA ε̄ act on the element's bending shape, so
that the analytic tangent K = Bᵀ U_pp B + Σ_k U_p,k ∇²p_k carries the consistent geometric
stiffness (compression lowers bending frequencies towards buckling, tension raises them).
g = −Bᵀ U_p with B = ∂(u, φ₁, φ₂)/∂w.

Mass (consistent, evaluated in the current element frame): axial linear, transverse and rotation
from the same interdependent shape functions, ∫ ρA NᵀN + ρI N_ψᵀN_ψ dx (rotary inertia in the
Timoshenko theory only).  M depends on the element's orientation β; at a static equilibrium
(q̇ = 0, q̈ = 0) the linearization needs only M(q₀), which :meth:`Model.mass_matrix` supplies.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import EquilibriumError
from .affine import Affine
from .base import ConfigurationMass, Constraint, Force

__all__ = [
    "BeamSection",
    "BeamElement",
    "RotationLock",
    "THEORIES",
    "GAUSS_X",
    "GAUSS_W",
    "section_properties",
    "timoshenko_shape_functions",
]

THEORIES = ("euler-bernoulli", "timoshenko")

# Gauss–Legendre points and weights on [0, 1], exact to degree 9 (planar and 3-D beams)
GAUSS_X, GAUSS_W = np.polynomial.legendre.leggauss(5)
GAUSS_X = 0.5 * (GAUSS_X + 1.0)
GAUSS_W = 0.5 * GAUSS_W
_D = np.array([[-1.0, 0, 0, 1, 0, 0], [0, -1.0, 0, 0, 1, 0]])  # d = D w


def section_properties(*, shape: str, dims: dict) -> dict:
    """Area, second moment, depth and shear coefficient of a standard section.

    rectangle (b, h): A = b h, I = b h³/12, κ = 5/6;  circle (d): A = π d²/4, I = π d⁴/64,
    κ = 9/10 (Cowper 1966 with ν = 0.3 gives 0.886; 0.9 is the usual rounded value).
    """
    if shape == "rectangle":
        b, h = dims["b"], dims["h"]
        return {"A": b * h, "I": b * h**3 / 12.0, "depth": h, "kappa": 5.0 / 6.0}
    if shape == "circle":
        d = dims["d"]
        return {"A": math.pi * d**2 / 4.0, "I": math.pi * d**4 / 64.0, "depth": d, "kappa": 0.9}
    raise ValueError(shape)


@dataclass(frozen=True)
class BeamSection:
    """Material and section of a beam: E, G [Pa], A [m²], I [m⁴], ρ [kg/m³], κ, theory."""

    E: float
    G: float
    A: float
    I: float  # noqa: E741 -- public field (constructor keyword, section.I)
    rho: float
    kappa: float
    theory: str = "euler-bernoulli"

    def shear_parameter(self, l0: float) -> float:
        """Φ = 12 EI/(κ G A l₀²) (0 for Euler–Bernoulli)."""
        if self.theory == "euler-bernoulli":
            return 0.0
        return 12.0 * self.E * self.I / (self.kappa * self.G * self.A * l0 * l0)

    def rotary_inertia(self) -> float:
        return self.rho * self.I if self.theory == "timoshenko" else 0.0


def timoshenko_shape_functions(xi, l0, Phi):
    """Interdependent interpolation (Friedman & Kosmatka 1993) on (w₁, ψ₁, w₂, ψ₂).

    Returns (N, dN/dx, N_ψ) with shapes (…, 4); Φ = 0 gives the cubic Hermite functions and
    N_ψ = dN/dx (Euler–Bernoulli).
    """
    xi = np.asarray(xi, dtype=float)[..., None]
    mu = 1.0 / (1.0 + Phi)
    x2, x3 = xi**2, xi**3
    N = mu * np.concatenate([
        2 * x3 - 3 * x2 - Phi * xi + 1 + Phi,
        l0 * (x3 - (2 + Phi / 2) * x2 + (1 + Phi / 2) * xi),
        -(2 * x3 - 3 * x2 - Phi * xi),
        l0 * (x3 - (1 - Phi / 2) * x2 - (Phi / 2) * xi),
    ], axis=-1)
    dN = mu * np.concatenate([
        (6 * x2 - 6 * xi - Phi) / l0,
        3 * x2 - (4 + Phi) * xi + 1 + Phi / 2,
        -(6 * x2 - 6 * xi - Phi) / l0,
        3 * x2 - (2 - Phi) * xi - Phi / 2,
    ], axis=-1)
    Npsi = mu * np.concatenate([
        6 * (x2 - xi) / l0,
        3 * x2 - (4 + Phi) * xi + 1 + Phi,
        -6 * (x2 - xi) / l0,
        3 * x2 - (2 - Phi) * xi,
    ], axis=-1)
    return N, dN, Npsi


def _wrap(a):
    return (a + math.pi) % (2.0 * math.pi) - math.pi


@dataclass(frozen=True, eq=False)
class BeamElement(Force, ConfigurationMass):
    """One co-rotational planar beam element on w = [x₁, y₁, θ₁, x₂, y₂, θ₂] (module docstring)."""

    name: str
    nodes: Affine  # 6 rows
    section: BeamSection
    l0: float

    def __post_init__(self):
        s, l0 = self.section, self.l0
        Phi = s.shear_parameter(l0)
        EI = s.E * s.I
        Kb = EI / (l0 * (1 + Phi)) * np.array([[4 + Phi, 2 - Phi], [2 - Phi, 4 + Phi]])
        N, dN, Npsi = timoshenko_shape_functions(GAUSS_X, l0, Phi)
        wq = GAUSS_W * l0
        # geometric matrix on the relative rotations: w(x) = N₂ φ₁ + N₄ φ₂ (zero end deflections)
        dphi = dN[:, [1, 3]]
        G = (dphi.T * wq) @ dphi / l0
        Mb = s.rho * s.A * (N.T * wq) @ N + s.rotary_inertia() * (Npsi.T * wq) @ Npsi
        M = np.zeros((6, 6))
        ax = [0, 3]
        M[np.ix_(ax, ax)] = s.rho * s.A * l0 / 6.0 * np.array([[2.0, 1.0], [1.0, 2.0]])
        bend = [1, 2, 4, 5]
        M[np.ix_(bend, bend)] = Mb
        object.__setattr__(self, "_Kb", Kb)
        object.__setattr__(self, "_G", G)
        object.__setattr__(self, "_Mloc", M)
        object.__setattr__(self, "Phi", Phi)

    affine_field = "nodes"  # idx = nodes.idx

    # -- kinematics --------------------------------------------------------------------------
    def _kinematics(self, w):
        d = _D @ w
        length = math.hypot(d[0], d[1])
        if length == 0.0:
            raise EquilibriumError("beam element collapsed to zero length", element=self.name)
        e = d / length
        n = np.array([-e[1], e[0]])
        beta = math.atan2(d[1], d[0])
        phi = np.array([_wrap(w[2] - beta), _wrap(w[5] - beta)])
        return d, length, e, n, phi

    def local_deformation(self, q):
        """(u, φ₁, φ₂): elongation and end rotations relative to the chord."""
        _, length, _, _, phi = self._kinematics(self.nodes(q))
        return np.array([length - self.l0, phi[0], phi[1]])

    def strain_parts(self, w):
        d, length, e, n, phi = self._kinematics(w)
        s, l0 = self.section, self.l0
        EA = s.E * s.A
        B = np.zeros((3, 6))
        B[0, [0, 1, 3, 4]] = [-e[0], -e[1], e[0], e[1]]
        for k, col in ((1, 2), (2, 5)):
            B[k, [0, 1, 3, 4]] = [n[0] / length, n[1] / length, -n[0] / length, -n[1] / length]
            B[k, col] = 1.0
        a = self._G @ phi
        eps = (length - l0) / l0 + 0.5 * phi @ a
        Up = np.concatenate([[EA * eps], EA * l0 * eps * a + self._Kb @ phi])
        c = np.concatenate([[1.0 / l0], a])
        Upp = EA * l0 * np.outer(c, c)
        Upp[1:, 1:] += EA * l0 * eps * self._G + self._Kb
        return d, length, e, n, B, Up, Upp

    # -- force element interface ------------------------------------------------------------
    def force(self, q, qd):
        w = self.nodes(q)
        *_, B, Up, _ = self.strain_parts(w)
        return -(self.nodes.C.T @ (B.T @ Up))

    def jacobians(self, q, qd):
        w = self.nodes(q)
        d, length, e, n, B, Up, Upp = self.strain_parts(w)
        H_l = _D.T @ (np.outer(n, n) / length) @ _D
        x, y = d
        r4 = (x * x + y * y) ** 2
        Hb = np.array([[2 * x * y, y * y - x * x], [y * y - x * x, -2 * x * y]]) / r4
        H_phi = -(_D.T @ Hb @ _D)
        Kw = B.T @ Upp @ B + Up[0] * H_l + (Up[1] + Up[2]) * H_phi
        C = self.nodes.C
        m = self.idx.size
        return C.T @ Kw @ C, np.zeros((m, m))

    # -- inertia -----------------------------------------------------------------------------
    def mass(self, q):
        """Consistent mass on idx in the current frame: Cᵀ Tᵀ M_loc T C."""
        w = self.nodes(q)
        _, _, e, n, _ = self._kinematics(w)
        R = np.array([e, n])
        T = np.zeros((6, 6))
        T[0:2, 0:2] = R
        T[3:5, 3:5] = R
        T[2, 2] = T[5, 5] = 1.0
        C = self.nodes.C
        return C.T @ (T.T @ self._Mloc @ T) @ C

    def strain_energy(self, q):
        u, p1, p2 = self.local_deformation(q)
        phi = np.array([p1, p2])
        eps = u / self.l0 + 0.5 * phi @ self._G @ phi
        s = self.section
        return 0.5 * s.E * s.A * self.l0 * eps**2 + 0.5 * phi @ self._Kb @ phi


@dataclass(frozen=True, eq=False)
class RotationLock(Constraint):
    """A beam node's angle follows a body direction: Φ = u × t(θ − c) = |u| sin(θ − c − α_u).

    ``stacked`` maps q to [u_x, u_y, θ] (u: a body-fixed direction, linear in q; θ: the node's
    angle coordinate); c is the constant offset that makes Φ = 0 in the assembled configuration.
    """

    name: str
    stacked: Affine
    offset: float
    affine_field = "stacked"  # idx = stacked.idx

    def _grad(self, w):
        ux, uy, th = w
        p = th - self.offset
        sp_, cp = math.sin(p), math.cos(p)
        phi = ux * sp_ - uy * cp
        grad = np.array([sp_, -cp, ux * cp + uy * sp_])
        H = np.array([[0.0, 0.0, cp], [0.0, 0.0, sp_], [cp, sp_, -phi]])
        return phi, grad, H

    def phi(self, q):
        return np.array([self._grad(self.stacked(q))[0]])

    def jac(self, q):
        return (self._grad(self.stacked(q))[1] @ self.stacked.C)[None, :]

    def hess(self, q, lam):
        H = self._grad(self.stacked(q))[2]
        C = self.stacked.C
        return lam[0] * (C.T @ H @ C)

    def gamma(self, q, qd):
        H = self._grad(self.stacked(q))[2]
        wd = self.stacked.rate(qd)
        return np.array([-(wd @ H @ wd)])

    def reaction(self, q, lam):
        """The moment λ|u| that welds the node to the body (Φ = |u| sin(θ − c − α_u))."""
        u = self.stacked(q)[:2]
        return {"key": "moment", "label": "moment", "unit": "N m",
                "value": float(lam[0]) * float(np.linalg.norm(u))}
