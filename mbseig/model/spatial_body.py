"""Spatial rigid bodies in natural coordinates: one basic point and three unit vectors.

A body's natural coordinates (García de Jalón & Bayo, "Kinematic and Dynamic Simulation of
Multibody Systems", 1994, ch. 3) are chosen by mbseig, not by the user (docs/spatial.md):

    q_b = [r₀; u; v; w]   (12 numbers)

r₀ is the body's basic point (its first carried point, else its centre of mass) and u, v, w are
body-fixed unit vectors equal to the global x, y, z axes at the reference configuration.  A body
point with reference position X and a body-fixed vector with reference components e are then

    r_P = r₀ + ξ₁ u + ξ₂ v + ξ₃ w,   ξ = X − X₀        (affine in q: r_P = C(ξ) q_b)
    e_b = e₁ u + e₂ v + e₃ w                           (linear in q)

so every point, direction and difference is an :class:`~mbseig.model.affine.Affine` map, the mass
matrix is constant and the six rigid-body conditions (unit lengths and right angles of u, v, w)
are quadratic.  With a = [1, ξ₁, ξ₂, ξ₃] and the frame written as a 3×4 matrix F = [r₀ u v w],
r_P = F a, so

    M_b = ∫ Cᵀ C dm = A ⊗ I₃,   A = ∫ a aᵀ dm = ┌ m      m ξ_Gᵀ              ┐
                                               └ m ξ_G  J_G + m ξ_G ξ_Gᵀ    ┘

with ξ_G the centre of mass and J_G = ∫ ρρᵀ dm = ½ tr(I_G) I₃ − I_G the second moment about it
(I_G the inertia tensor about the centre of mass, global axes at the reference).  A is positive
semidefinite exactly when I_G satisfies the triangle inequalities; the kinetic energy ½ q̇ᵀM q̇
equals ½ m v_G² + ½ ωᵀ I_G ω for every motion of the frame (tests/test_spatial_body.py).
"""

from __future__ import annotations

import numpy as np

from .affine import Affine, combine, identity_of, shared_constant

__all__ = [
    "FRAME_SIZE",
    "GROUND",
    "frame_gravity",
    "frame_of",
    "frame_point",
    "frame_vector",
    "inertia_problem",
    "point_matrices",
    "point_matrix",
    "second_moment",
    "spatial_mass_matrix",
    "vector_matrix",
]

FRAME_SIZE = 12
#: the ground frame: origin at 0, axes equal to the global axes (local coordinates are global)
GROUND = Affine.constant(np.concatenate([np.zeros(3), np.eye(3).ravel()]))


def frame_of(origin: Affine, triad_idx) -> Affine:
    """The 12-row frame map [r₀; u; v; w] of a body whose origin is ``origin`` and whose unit
    vectors are the free coordinates ``triad_idx`` (9 indices, u then v then w)."""
    triad_idx = np.asarray(triad_idx, dtype=np.intp)
    o = origin.idx
    if (o.size == 3 and triad_idx.size == 9 and origin.C.shape == (3, 3) and o[0] < o[1] < o[2]
            and o[2] < triad_idx[0] and np.all(np.diff(triad_idx) > 0)
            and np.array_equal(origin.C, _EYE3)):
        # the common frame (free origin allocated before its sorted triad): what combine forms,
        # the identity on the concatenated indices (one read-only identity shared by all such
        # frames: a beam of 10⁵ nodes), without its general-purpose work
        return Affine(np.concatenate([o, triad_idx]), identity_of(FRAME_SIZE),
                      np.concatenate([origin.d, np.zeros(9)]))
    return combine([(1.0, origin), (1.0, Affine.select(triad_idx))], stack=True)


_EYE3 = np.eye(3)


_I3 = np.eye(3)[:, None, :]


def _kron_i3(c) -> np.ndarray:
    """cᵀ ⊗ I₃ (3×12) for the 4 coefficients c: entry [i, 3k + j] = c_k δ_ij, the very products
    ``np.kron`` forms (signed zeros included), without its general-purpose overhead (a spatial
    case of 10⁴ bodies builds ≈ 10⁵ of these)."""
    return (np.asarray(c, float)[None, :, None] * _I3).reshape(3, FRAME_SIZE)


def point_matrix(local) -> np.ndarray:
    """C(ξ) (3×12): r_P = C(ξ) [r₀; u; v; w] for a point with local coordinates ξ."""
    x, y, z = np.asarray(local, float)
    return _kron_i3((1.0, x, y, z))


def point_matrices(locals_) -> np.ndarray:
    """C(ξ) of many points (n, 3, 12): :func:`point_matrix` of each row of ``locals_``."""
    xi = np.asarray(locals_, float).reshape(-1, 3)
    c = np.hstack([np.ones((xi.shape[0], 1)), xi])
    return (c[:, None, :, None] * _I3[None]).reshape(-1, 3, FRAME_SIZE)


def vector_matrix(local) -> np.ndarray:
    """V(e) (3×12): e_b = V(e) [r₀; u; v; w] for a body vector with local components e."""
    x, y, z = np.asarray(local, float)
    return _kron_i3((0.0, x, y, z))


def _mapped(frame: Affine, T: np.ndarray) -> Affine:
    if frame.C is identity_of(FRAME_SIZE):
        # a frame on its own coordinates (a beam node): T · I is T, kept once for all the
        # points at one local position (T + 0: its zeros unsigned; no value changes)
        return Affine(frame.idx, shared_constant(T + 0.0), T @ frame.d)
    return Affine(frame.idx, T @ frame.C, T @ frame.d)


def frame_point(frame: Affine, local) -> Affine:
    """Affine map of the body point with local coordinates ξ."""
    return _mapped(frame, point_matrix(local))


def frame_vector(frame: Affine, local) -> Affine:
    """Linear map of the body-fixed vector with local components e."""
    return _mapped(frame, vector_matrix(local))


def second_moment(inertia) -> np.ndarray:
    """J = ∫ρρᵀ dm = ½ tr(I) I₃ − I from the inertia tensor I = tr(J) I₃ − J."""
    inertia = np.asarray(inertia, float)
    return 0.5 * np.trace(inertia) * np.eye(3) - inertia


def spatial_mass_matrix(mass: float, com_local, inertia) -> np.ndarray:
    """Constant 12×12 mass matrix A ⊗ I₃ of a body on [r₀; u; v; w] (module docstring)."""
    return spatial_mass_matrices(np.array([mass], float), com_local,
                                 np.asarray(inertia, float)[None])[0]


def spatial_mass_matrices(masses, com_local, inertias) -> np.ndarray:
    """:func:`spatial_mass_matrix` at B masses (B,) and inertias (B, 3, 3) of one body (the
    same centre of mass): (B, 12, 12), A = [[m, m ξ_Gᵀ], [m ξ_G, J + m ξ_G ξ_Gᵀ]] with J the
    second moment (:func:`second_moment`) of each inertia."""
    xg = np.asarray(com_local, float)
    m = np.asarray(masses, float)
    J = np.asarray(inertias, float)
    B = m.size
    A = np.empty((B, 4, 4))
    A[:, 0, 0] = m
    A[:, 0, 1:] = A[:, 1:, 0] = m[:, None] * xg
    second = 0.5 * np.trace(J, axis1=1, axis2=2)[:, None, None] * np.eye(3) - J
    A[:, 1:, 1:] = second + m[:, None, None] * np.outer(xg, xg)
    return (A[:, :, None, :, None] * _EYE3[None, None, :, None, :]).reshape(
        B, FRAME_SIZE, FRAME_SIZE)


def frame_gravity(mass: float, com_local, gravity) -> np.ndarray:
    """Generalized weight on the frame coordinates: C(ξ_G)ᵀ m g (12,)."""
    return point_matrix(com_local).T @ (mass * np.asarray(gravity, float))


def inertia_problem(inertia, *, rtol: float = 1e-12) -> str | None:
    """Why ``inertia`` (3×3, about the centre of mass) is not a rigid body's inertia tensor, or
    None: it must be symmetric, positive definite and satisfy the triangle inequalities
    I₁ ≤ I₂ + I₃ of its principal moments (equality: a plane lamina)."""
    inertia = np.asarray(inertia, float)
    scale = float(np.max(np.abs(inertia), initial=0.0))
    if not np.all(np.isfinite(inertia)):
        return "inertia must be finite"
    if np.max(np.abs(inertia - inertia.T), initial=0.0) > rtol * max(scale, 1e-300):
        return "inertia tensor must be symmetric"
    p = np.linalg.eigvalsh(0.5 * (inertia + inertia.T))
    if p[0] <= 0:
        return (f"inertia tensor must be positive definite (principal moments "
                f"{', '.join(f'{x:.6g}' for x in p)})")
    if p[2] > (p[0] + p[1]) * (1 + 1e-12):
        return (f"principal moments {p[0]:.6g}, {p[1]:.6g}, {p[2]:.6g} violate the triangle "
                f"inequality I3 <= I1 + I2 (no mass distribution has them)")
    return None
