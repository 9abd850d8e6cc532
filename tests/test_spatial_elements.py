"""Spatial body, joints and forces: mass matrix against the kinetic energy, every Jacobian and
Hessian against the complex step (exact to rounding for these analytic functions) or, where the
element uses atan2 (angle driver, torsional spring), 4th-order central differences, at random
moving states (q off the constraint manifold and q̇ ≠ 0, so velocity terms are exercised).

Tolerances: complex step h = 1e-30, agreement to 1e-10 relative to the Jacobian's size;
central differences h = 1e-5, 1e-7 relative (truncation ~h⁴, rounding ~ε/h).
Kinetic energy: closed form ½ m v_G² + ½ ωᵀ R I_G Rᵀ ω (rigid-body kinematics), 1e-12 relative.
"""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation
from test_jacobians import central  # 4th-order central differences, h = 1e-5

from mbseig.model.affine import Affine, combine
from mbseig.model.spatial_body import (
    GROUND,
    frame_of,
    frame_point,
    frame_vector,
    inertia_problem,
    point_matrix,
    spatial_mass_matrix,
)
from mbseig.model.spatial_forces import (
    BodyMoment,
    PointFollowerForce,
    QuadraticSpringDamper,
    Rotor,
    SpatialTorsional,
    bushing_rows,
)
from mbseig.model.spatial_joints import (
    JOINT_ROWS,
    QuadraticConstraint,
    SpatialAngleDriver,
    angle_rows,
    joint_rows,
    triad_constraint,
)

CS_RTOL = 1e-10
CD_RTOL = 1e-7


def cstep(f, x, h=1e-30):
    """Jacobian of f at x by the complex step (no subtractive cancellation)."""
    x = np.asarray(x, float)
    cols = []
    for i in range(x.size):
        xc = x.astype(complex)
        xc[i] += 1j * h
        cols.append(np.imag(f(xc)) / h)
    return np.column_stack(cols)


def close(a, b, rtol):
    scale = max(np.abs(a).max(), np.abs(b).max(), 1e-300)
    assert np.abs(a - b).max() <= rtol * scale, np.abs(a - b).max() / scale


def random_body(rng):
    m = rng.uniform(0.5, 3.0)
    p = np.sort(rng.uniform(0.2, 1.0, 3))
    p[2] = min(p[2], p[0] + p[1])  # triangle inequality
    R = Rotation.random(random_state=rng.integers(1 << 30)).as_matrix()
    return m, rng.normal(size=3) * 0.3, R @ np.diag(p) @ R.T


# ---------------------------------------------------------------------------------------------
@pytest.mark.parametrize("seed", range(5))
def test_mass_matrix_kinetic_energy(seed):
    """½ żᵀ M ż = ½ m v_G² + ½ ωᵀ (R I_G Rᵀ) ω for a random body, rotation, ω and ṙ₀."""
    rng = np.random.default_rng(seed)
    m, xg, I_G = random_body(rng)
    M = spatial_mass_matrix(m, xg, I_G)
    R = Rotation.random(random_state=seed).as_matrix()
    w, v0 = rng.normal(size=3), rng.normal(size=3)
    zdot = np.concatenate([v0] + [np.cross(w, R[:, k]) for k in range(3)])
    vG = v0 + np.cross(w, R @ xg)
    T_ref = 0.5 * m * vG @ vG + 0.5 * w @ (R @ I_G @ R.T) @ w
    assert 0.5 * zdot @ M @ zdot == pytest.approx(T_ref, rel=1e-12)
    # the CoM: ∫C dm = m C(ξ_G), i.e. the first block row of M is m C(ξ_G)
    np.testing.assert_allclose(M[:3], m * point_matrix(xg), rtol=1e-14, atol=1e-14)


@pytest.mark.parametrize("inertia, ok", [
    (np.diag([1.0, 2.0, 2.5]), True),
    (np.diag([1.0, 1.0, 2.0]), True),  # plane lamina: equality allowed
    (np.diag([1.0, 1.0, 2.5]), False),  # triangle inequality violated
    (np.diag([1.0, -1.0, 1.0]), False),  # not positive definite
    (np.array([[1.0, 0.1, 0], [0.0, 1, 0], [0, 0, 1]]), False),  # not symmetric
])
def test_inertia_validation(inertia, ok):
    assert (inertia_problem(inertia) is None) == ok


# ---------------------------------------------------------------------------------------------
def two_frames(ground_first=False):
    """Two free frames on q[0:12], q[12:24] (or ground and one frame on q[0:12])."""
    f2 = frame_of(Affine.select(np.arange(12, 15)), np.arange(15, 24))
    f1 = frame_of(Affine.select(np.arange(0, 3)), np.arange(3, 12))
    if ground_first:
        return (GROUND, frame_of(Affine.select(np.arange(0, 3)), np.arange(3, 12))), 12
    return (f1, f2), 24


def moving_state(rng, n):
    q = rng.normal(size=n) * 0.3
    for k in range(n // 12):  # near-orthonormal frames, perturbed: off the manifold
        R = Rotation.random(random_state=rng.integers(1 << 30)).as_matrix()
        q[12 * k + 3:12 * k + 12] = R.T.ravel() + 0.05 * rng.normal(size=9)
    return q, rng.normal(size=n)


def scatter_full(el, local, n):
    out = np.zeros((n, n), dtype=local.dtype)
    out[np.ix_(el.idx, el.idx)] = local
    return out


def check_constraint(c, n, rng):
    q, qd = moving_state(rng, n)
    lam = rng.normal(size=c.n_eq)

    def phi(x):
        return c.phi(x)

    def jac_full(x):
        J = np.zeros((c.n_eq, n), dtype=x.dtype)
        J[:, c.idx] = c.jac(x)
        return J

    close(jac_full(q), cstep(phi, q), CS_RTOL)
    H = scatter_full(c, c.hess(q, lam), n)
    close(H, cstep(lambda x: jac_full(x).T @ lam, q), CS_RTOL)
    # γ = −(Φ_q q̇)_q q̇
    close(c.gamma(q, qd), -cstep(lambda x: jac_full(x) @ qd, q) @ qd, CS_RTOL)


def test_triad_constraint():
    rng = np.random.default_rng(1)
    (f1, _), _n = two_frames()
    check_constraint(triad_constraint("t", f1), 12, rng)


@pytest.mark.parametrize("kind", sorted(JOINT_ROWS))
@pytest.mark.parametrize("ground", [False, True])
def test_joint_derivatives(kind, ground):
    rng = np.random.default_rng(hash(kind) % 1000 + ground)
    frames, n = two_frames(ground)
    a = np.array([0.3, -0.5, 0.8])
    a /= np.linalg.norm(a)
    b = np.cross(a, [1.0, 0.0, 0.0])
    b /= np.linalg.norm(b)
    axes = (b, a) if kind == "universal" else (a,)
    rows = joint_rows(kind, frames, (rng.normal(size=3), rng.normal(size=3)), axes, 0.7)
    c = QuadraticConstraint(kind, rows, wrench=(12 if not ground else 0, np.zeros(3), "b"))
    assert c.n_eq == JOINT_ROWS[kind]
    check_constraint(c, n, rng)


def test_joint_rows_vanish_and_are_independent_at_the_reference():
    """At the reference (frames = identity triads at their origins) every joint's Φ is 0 and
    Φ_q has full row rank (no redundant equation)."""
    frames, _n = two_frames()
    o1, o2 = np.array([0.1, 0.2, 0.3]), np.array([-0.4, 0.5, 0.0])
    q = np.concatenate([o1, np.eye(3).ravel(), o2, np.eye(3).ravel()])
    at = np.array([0.3, 0.3, 0.3])
    a = np.array([0.0, 0.6, 0.8])
    for kind in JOINT_ROWS:
        axes = (a, np.cross(a, [1.0, 0.0, 0.0])) if kind == "universal" else (a,)
        c = QuadraticConstraint(kind, joint_rows(kind, frames, (at - o1, at - o2), axes, 1.0))
        assert np.abs(c.phi(q)).max() < 1e-15
        assert np.linalg.matrix_rank(c.jac(q)) == c.n_eq


def test_angle_driver_and_torsional_derivatives():
    rng = np.random.default_rng(5)
    frames, n = two_frames()
    axis = np.array([0.0, 0.6, 0.8])
    rows = angle_rows(frames, axis)
    dirs = rows.aff
    drv = SpatialAngleDriver("d", dirs, 0.3, rows=rows)
    q, qd = moving_state(rng, n)
    lam = np.array([0.7])

    def jac_full(x):
        J = np.zeros((1, n))
        J[:, drv.idx] = drv.jac(x)
        return J

    close(jac_full(q), central(lambda x: drv.phi(x), q), CD_RTOL)
    close(scatter_full(drv, drv.hess(q, lam), n), central(lambda x: jac_full(x).T @ lam, q),
          CD_RTOL)
    close(drv.gamma(q, qd), -central(lambda x: jac_full(x) @ qd, q) @ qd, CD_RTOL)
    el = SpatialTorsional("k", dirs, 3.0, 0.4, 0.2, rows=rows)
    check_force(el, n, rng, diff=central, rtol=CD_RTOL)


def test_angle_is_the_rotation_about_the_axis():
    """Rotating body 2 by φ about the axis (right-handed) gives θ = φ (Rodrigues' formula)."""
    frames, _n = two_frames(ground_first=True)
    axis = np.array([2.0, -1.0, 2.0]) / 3.0
    rows = angle_rows(frames, axis)
    drv = SpatialAngleDriver("d", rows.aff, 0.0, rows=rows)
    for phi in (0.3, -1.2, 2.9):
        R = Rotation.from_rotvec(phi * axis).as_matrix()
        q = np.concatenate([np.zeros(3), R.T.ravel()])  # u, v, w = columns of R
        assert drv.angle(q) == pytest.approx(phi, abs=1e-14)


# ---------------------------------------------------------------------------------------------
def check_force(el, n, rng, diff=cstep, rtol=CS_RTOL):
    q, qd = moving_state(rng, n)

    def g(x, v):
        out = np.zeros(n, dtype=np.result_type(x, v))
        np.add.at(out, el.idx, el.force(x, v))
        return out

    K, C = el.jacobians(q, qd)
    close(scatter_full(el, K, n), -diff(lambda x: g(x, qd), q), rtol)
    close(scatter_full(el, C, n), -diff(lambda v: g(q, v), qd), rtol)


@pytest.mark.parametrize("follower", [False, True])
def test_body_moment(follower):
    rng = np.random.default_rng(11)
    (f1, _), _n = two_frames()
    T = frame_vector(f1, [0.3, -1.0, 2.0]) if follower else Affine.constant([0.3, -1.0, 2.0])
    check_force(BodyMoment("T", combine([(1.0, f1), (1.0, T)], stack=True)), 12, rng)


def test_point_follower_force():
    rng = np.random.default_rng(12)
    (f1, _), _n = two_frames()
    st = combine([(1.0, frame_point(f1, [0.2, 0.1, -0.3])), (1.0, frame_vector(f1, [0, 0, 5.0]))],
                 stack=True)
    check_force(PointFollowerForce("F", st), 12, rng)


def test_rotor_jacobians_and_skew_gyroscopic_matrix():
    rng = np.random.default_rng(13)
    (f1, _), _n = two_frames()
    r = Rotor("rotor", f1, np.array([0.0, 0.6, 0.8]), polar_inertia=0.4, speed=30.0)
    check_force(r, 12, rng)
    # on the constraint manifold of an orthonormal frame, Nᵀ C N is skew and ∝ Ω
    c = triad_constraint("t", f1)
    R = Rotation.random(random_state=3).as_matrix()
    q = np.concatenate([rng.normal(size=3), R.T.ravel()])
    Nb = np.linalg.svd(c.jac(q))[2][c.n_eq:].T
    _, C = r.jacobians(q, np.zeros(12))
    P = Nb.T @ C @ Nb
    assert np.abs(P + P.T).max() <= 1e-14 * np.abs(P).max()
    _, C2 = Rotor("r2", f1, r.axis, 0.4, 60.0).jacobians(q, np.zeros(12))
    np.testing.assert_allclose(Nb.T @ C2 @ Nb, 2 * P, rtol=1e-13, atol=1e-13 * np.abs(P).max())


@pytest.mark.parametrize("ground", [False, True])
def test_bushing_jacobians(ground):
    rng = np.random.default_rng(14 + ground)
    frames, n = two_frames(ground)
    rows = bushing_rows(frames, (rng.normal(size=3), rng.normal(size=3)))
    Kb = rng.normal(size=(6, 6))
    Db = rng.normal(size=(6, 6))
    check_force(QuadraticSpringDamper("b", rows, Kb, Db), n, rng)


def test_bushing_strains_are_displacement_and_rotation():
    """Strains of a small rigid motion of b2 relative to ground: d = t + θ × (P − X₀) in
    global axes and the rotation vector θ, to second order (1e-10 at |θ| = 1e-5)."""
    frames, _n = two_frames(ground_first=True)
    at = np.array([0.5, -0.2, 0.1])
    o2 = np.array([0.1, 0.1, 0.1])
    rows = bushing_rows(frames, (at, at - o2))
    th, t = np.array([1.0, -2.0, 0.5]) * 1e-5, np.array([3.0, 1.0, -2.0]) * 1e-5
    R = Rotation.from_rotvec(th).as_matrix()
    q = np.concatenate([o2 + t, R.T.ravel()])
    e = QuadraticSpringDamper("b", rows, np.eye(6), np.zeros((6, 6))).strains(q)
    d_ref = t + (R - np.eye(3)) @ (at - o2)
    np.testing.assert_allclose(e[:3], d_ref, atol=1e-14)
    np.testing.assert_allclose(e[3:], th, rtol=1e-9)
