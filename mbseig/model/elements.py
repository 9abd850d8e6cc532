"""Element kernels: inertia, constraints and forces on affine point maps.

Sign conventions (docs/design.md, "Equations" and "Linearization"):

    M q̈ + Φ_qᵀ λ = g(q, q̇),        K = −∂g/∂q,   C = −∂g/∂q̇,   H(λ) = Σ_k λ_k ∇²Φ_k.

Each constraint returns Φ (its rows), the rows of Φ_q on its local indices, H(λ) on the same
indices, and γ = −(Φ_q q̇)_q q̇ for the acceleration level.  Each force returns its contribution to
g and to (K, C) on its local indices.  All Jacobians are analytic and are tested against central
and complex-step differences in tests/test_jacobians.py.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..errors import EquilibriumError
from .affine import J2, Affine, combine
from .base import Constraint, Force
from .batched import spring_forces, spring_tangents

__all__ = [
    "body_mass_matrix",
    "body_point",
    "body_direction",
    "DistanceConstraint",
    "LinearConstraint",
    "SpringDamper",
    "TorsionalSpringDamper",
    "FollowerForce",
]


# ---------------------------------------------------------------------------------------------
# Planar rigid body in natural coordinates
# ---------------------------------------------------------------------------------------------
def body_mass_matrix(mass: float, inertia_g: float, com: tuple[float, float], length: float):
    """Constant 4×4 mass matrix of a planar body on q_b = [x_i, y_i, x_j, y_j].

    M = ∫ Cᵀ C dm with C = [(1 − c1) I − c2 J, c1 I + c2 J], c1 = x̄/L, c2 = ȳ/L:

        M = [[ (m − 2 m x̄_G/L + I_i/L²) I ,  (m x̄_G/L − I_i/L²) I + (m ȳ_G/L) J ],
             [ (m x̄_G/L − I_i/L²) I − (m ȳ_G/L) J ,      (I_i/L²) I          ]]

    where I_i = I_G + m (x̄_G² + ȳ_G²) is the polar moment about basic point i.
    """
    xg, yg = com
    L = length
    I_i = inertia_g + mass * (xg * xg + yg * yg)
    I2 = np.eye(2)
    a = mass - 2.0 * mass * xg / L + I_i / L**2
    off = (mass * xg / L - I_i / L**2) * I2 + (mass * yg / L) * J2
    return np.block([[a * I2, off], [off.T, (I_i / L**2) * I2]])


def body_point(ri: Affine, rj: Affine, local, length: float) -> Affine:
    """Affine map of the body point with local coordinates (x̄, ȳ): r_P = C q_b."""
    c1, c2 = local[0] / length, local[1] / length
    return combine([((1.0 - c1) * np.eye(2) - c2 * J2, ri), (c1 * np.eye(2) + c2 * J2, rj)])


def body_direction(ri: Affine, rj: Affine, local, length: float) -> Affine:
    """Body-fixed vector with local components (u, v) per unit length: (u I + v J)(r_j − r_i)/L."""
    F = (local[0] * np.eye(2) + local[1] * J2) / length
    return combine([(F, rj), (-F, ri)])


# ---------------------------------------------------------------------------------------------
# Constraints
# ---------------------------------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class DistanceConstraint(Constraint):
    """Φ = d·d − L² with d = r_b − r_a (a rigid length or a massless rod)."""

    glyph = "rod"

    name: str
    diff: Affine
    length: float
    affine_field = "diff"  # idx = diff.idx

    def phi(self, q):
        d = self.diff(q)
        return np.array([d @ d - self.length**2])

    def jac(self, q):
        return (2.0 * self.diff(q) @ self.diff.C)[None, :]

    def hess(self, q, lam):
        return 2.0 * lam[0] * (self.diff.C.T @ self.diff.C)

    def gamma(self, q, qd):
        dd = self.diff.rate(qd)
        return np.array([-2.0 * dd @ dd])

    def scale(self):
        """Typical magnitude of Φ, to judge residuals: L²."""
        return max(self.length**2, 1e-300)

    def reaction(self, q, lam):
        """Axial force 2λL, tension positive."""
        return {"key": "axial_force", "label": "axial force (tension +)",
                "value": 2.0 * float(lam[0]) * self.length, "unit": "N"}


@dataclass(frozen=True, eq=False)
class LinearConstraint(Constraint):
    """Φ = G r(q) − b: a fixed point, a point on a fixed line, a point attached to a body."""

    glyph = "guide"

    name: str
    point: Affine
    G: np.ndarray
    b: np.ndarray
    length_scale: float = 1.0
    # ("carries", BODY, POINT): a point carried by a spatial body (reactions); keyword-only
    role: tuple = field(default=(), kw_only=True)

    @property
    def n_eq(self):
        return self.G.shape[0]

    affine_field = "point"  # idx = point.idx

    def phi(self, q):
        return self.G @ self.point(q) - self.b

    def jac(self, q):
        return self.G @ self.point.C

    def hess(self, q, lam):
        n = self.point.idx.size
        return np.zeros((n, n))

    def gamma(self, q, qd):
        return np.zeros(self.n_eq)

    def scale(self):
        return self.length_scale

    def reaction(self, q, lam):
        """The force −Gᵀλ the constraint exerts on its point."""
        return {"key": "force", "label": "force", "value": [float(x) for x in -(self.G.T @ lam)],
                "unit": "N"}


# ---------------------------------------------------------------------------------------------
# Forces
# ---------------------------------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class SpringDamper(Force):
    """Linear spring (stiffness k, free length l0) and dashpot c between two points.

    d = r_b − r_a, l = |d|, e = d/l.  The force on b is −f with f = k (l − l0) e + c (e·ḋ) e and
    g = −Dᵀ f.  In one dimension the extension is signed, f = k (d − l0) + c ḋ, so that points
    may pass each other (chains written in displacement coordinates).
    """

    glyph = "spring"

    name: str
    diff: Affine
    stiffness: float
    free_length: float
    damping: float = 0.0

    affine_field = "diff"  # idx = diff.idx

    def members(self, q, qd):
        """d, ḋ and the parameters as a batch of one member (:mod:`mbseig.model.batched`)."""
        D = self.diff.C

        def arr(x):
            return np.array([x], dtype=float)

        return (self.diff(q)[None], (D @ qd[self.idx])[None], arr(self.stiffness),
                arr(self.free_length), arr(self.damping), lambda k: self.name)

    def force(self, q, qd):
        return -(self.diff.C.T @ spring_forces(*self.members(q, qd))[0])

    def jacobians(self, q, qd):
        D = self.diff.C
        Kf, Cf = spring_tangents(*self.members(q, qd))
        return D.T @ Kf[0] @ D, D.T @ Cf[0] @ D


def angle_derivatives(v):
    """Gradient and Hessian of the polar angle α = atan2(v_y, v_x)."""
    x, y = v
    r2 = x * x + y * y
    grad = np.array([-y, x]) / r2
    hess = np.array([[2 * x * y, y * y - x * x], [y * y - x * x, -2 * x * y]]) / r2**2
    return grad, hess


def relative_angle(dirs: Affine, q, sense: float, name: str):
    """θ = sense · atan2(a × b, a · b) of the stacked directions [a; b] = ``dirs(q)``, with its
    gradient g and Hessian H with respect to [a; b] (4-vectors, 4×4), shared by the torsional
    spring and the angle driver so that both measure the same angle the same way."""
    ax, ay, bx, by = dirs(q).tolist()  # (scalar arithmetic: called at every evaluation)
    ra, rb = ax * ax + ay * ay, bx * bx + by * by
    if ra == 0.0 or rb == 0.0:
        raise EquilibriumError("direction of zero length: angle undefined", element=name)
    # g = sense [−∇α(a); ∇α(b)], H = sense diag(−∇²α(a), ∇²α(b)) (angle_derivatives)
    g = np.array([ay / ra, -ax / ra, -by / rb, bx / rb]) * sense
    sa, sb = -sense / (ra * ra), sense / (rb * rb)
    pa, ma, pb, mb = (2 * ax * ay * sa, (ay * ay - ax * ax) * sa,
                      2 * bx * by * sb, (by * by - bx * bx) * sb)
    H = np.array([[pa, ma, 0.0, 0.0], [ma, -pa, 0.0, 0.0], [0.0, 0.0, pb, mb], [0.0, 0.0, mb, -pb]])
    return _theta(ax, ay, bx, by, sense), g, H


def _theta(ax, ay, bx, by, sense):
    return sense * math.atan2(ax * by - ay * bx, ax * bx + ay * by)


def relative_angle_only(dirs: Affine, q, sense: float, name: str) -> float:
    """θ of :func:`relative_angle` alone (the same check and θ, without g and H)."""
    ax, ay, bx, by = dirs(q).tolist()
    if ax * ax + ay * ay == 0.0 or bx * bx + by * by == 0.0:
        raise EquilibriumError("direction of zero length: angle undefined", element=name)
    return _theta(ax, ay, bx, by, sense)


@dataclass(frozen=True, eq=False)
class TorsionalSpringDamper(Force):
    """Torsional spring-damper on the relative angle between two planar directions.

    θ = atan2(a × b, a · b) is the angle from direction a (body 1 or ground) to direction b
    (body 2), counterclockwise; ``sense = -1`` measures it clockwise.  The torque on body 2 is
    τ = −k (θ − θ0) − c θ̇, so g = −(k (θ − θ0) + c θ̇) ∇θ, with θ − θ0 wrapped to (−π, π].
    """

    glyph = "torsional"

    name: str
    dirs: Affine  # stacked [a; b] (4 rows)
    stiffness: float
    damping: float
    angle0: float
    sense: float = 1.0

    affine_field = "dirs"  # idx = dirs.idx

    def angle(self, q):
        return relative_angle(self.dirs, q, self.sense, self.name)[0]

    def torque_parts(self, q, qd):
        W = self.dirs.C
        theta, g, H = relative_angle(self.dirs, q, self.sense, self.name)
        dtheta = (theta - self.angle0 + math.pi) % (2 * math.pi) - math.pi
        wd = W @ qd[self.idx]
        theta_dot = g @ wd
        tau = self.stiffness * dtheta + self.damping * theta_dot
        return W, g, H, wd, tau

    def force(self, q, qd):
        W, g, H, wd, tau = self.torque_parts(q, qd)
        return -tau * (W.T @ g)

    def jacobians(self, q, qd):
        W, g, H, wd, tau = self.torque_parts(q, qd)
        Kw = np.outer(g, self.stiffness * g + self.damping * (H @ wd)) + tau * H
        return W.T @ Kw @ W, self.damping * (W.T @ np.outer(g, g) @ W)


@dataclass(frozen=True, eq=False)
class FollowerForce(Force):
    """Force of magnitude f at a body point along a body-fixed direction (non-conservative).

    F = f u(q) with u = (ū I + v̄ J)(r_j − r_i)/L linear in q, so g = C_Pᵀ f u(q) and
    K = −f C_Pᵀ C_u, which is not symmetric: never put such a K through a symmetric solver.
    """

    glyph = "load"
    scalable_load = True

    name: str
    stacked: Affine  # [r_P; u] on the union of their indices (4 rows)
    magnitude: float

    affine_field = "stacked"  # idx = stacked.idx

    def force(self, q, qd):
        Cp = self.stacked.C[:2]
        u = self.stacked(q)[2:]
        return Cp.T @ (self.magnitude * u)

    def jacobians(self, q, qd):
        Cp, Cu = self.stacked.C[:2], self.stacked.C[2:]
        n = self.idx.size
        return -self.magnitude * (Cp.T @ Cu), np.zeros((n, n))
