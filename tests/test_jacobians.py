"""Analytic element Jacobians against central differences (DESIGN §4).

Reference: fourth-order central differences with step h = 1e-5 (truncation O(h⁴) ≈ 1e-20,
rounding ≈ ε/h ≈ 1e-11 relative); tolerance 1e-7 relative to the Jacobian's largest entry.
States are random (fixed seeds) with non-zero velocities, so the velocity-dependent parts of
K (damper and torsional-damper terms) are exercised too.
"""

import numpy as np
import pytest

from mbseig.model.affine import Affine, combine
from mbseig.model.elements import (
    DistanceConstraint,
    FollowerForce,
    LinearConstraint,
    SpringDamper,
    TorsionalSpringDamper,
    body_direction,
    body_point,
)

RTOL = 1e-7
ATOL = 1e-9  # times the size of the function differenced: rounding floor ε·|f|/h ≈ 1e-11·|f|


def central(f, x, h=1e-5):
    """Jacobian of f at x by the 4th-order central difference."""
    x = np.asarray(x, float)
    cols = []
    for i in range(x.size):
        e = np.zeros_like(x)
        e[i] = h
        cols.append((-f(x + 2 * e) + 8 * f(x + e) - 8 * f(x - e) + f(x - 2 * e)) / (12 * h))
    return np.column_stack(cols)


def assert_jac(analytic, numeric, fscale=1.0):
    """|analytic − numeric| ≤ RTOL·max|J| + ATOL·fscale (fscale: size of the function values)."""
    scale = max(np.abs(numeric).max(), np.abs(analytic).max())
    assert np.abs(analytic - numeric).max() <= RTOL * scale + ATOL * max(fscale, 1.0)


def free_point(i0, dim):
    return Affine.select(np.arange(i0, i0 + dim))


def full(idx, local, n):
    out = np.zeros((n, n))
    out[np.ix_(idx, idx)] = local
    return out


def check_force(el, n, rng):
    q, qd = rng.normal(size=n), rng.normal(size=n)

    def g(qq, vv):
        out = np.zeros(n)
        np.add.at(out, el.idx, el.force(qq, vv))
        return out

    K, C = el.jacobians(q, qd)
    fs = np.abs(g(q, qd)).max()
    assert_jac(full(el.idx, K, n), -central(lambda x: g(x, qd), q), fs)
    assert_jac(full(el.idx, C, n), -central(lambda v: g(q, v), qd), fs)


@pytest.mark.parametrize("dim", [1, 2, 3])
@pytest.mark.parametrize("seed", range(3))
def test_spring_damper(dim, seed):
    rng = np.random.default_rng(seed)
    a, b = free_point(0, dim), free_point(dim, dim)
    el = SpringDamper("s", b - a, stiffness=3.0, free_length=0.7, damping=0.4)
    check_force(el, 2 * dim, rng)


def test_spring_to_ground_and_zero_free_length():
    rng = np.random.default_rng(7)
    a, b = Affine.constant([0.3, -0.2]), free_point(0, 2)
    check_force(SpringDamper("s", b - a, 5.0, 0.0, 0.1), 2, rng)


@pytest.mark.parametrize("sense", [1.0, -1.0])
@pytest.mark.parametrize("seed", range(3))
def test_torsional_between_bodies(sense, seed):
    rng = np.random.default_rng(seed)
    p = [free_point(2 * k, 2) for k in range(4)]  # body 1: p0-p1, body 2: p2-p3
    d1 = body_direction(p[0], p[1], (1.0, 0.0), 1.0)
    d2 = body_direction(p[2], p[3], (1.0, 0.0), 1.0)
    el = TorsionalSpringDamper("t", combine([(1.0, d1), (1.0, d2)], stack=True), 2.0, 0.3, 0.4,
                               sense)
    check_force(el, 8, rng)


def test_torsional_to_ground():
    rng = np.random.default_rng(3)
    ground = Affine.constant([1.0, 0.0])
    body = body_direction(Affine.constant([0.0, 0.0]), free_point(0, 2), (1.0, 0.0), 1.0)
    el = TorsionalSpringDamper("t", combine([(1.0, ground), (1.0, body)], stack=True), 2.0, 0.3,
                               1.0, -1.0)
    check_force(el, 2, rng)


def test_follower_force():
    rng = np.random.default_rng(11)
    ri, rj = free_point(0, 2), free_point(2, 2)
    p = body_point(ri, rj, (0.8, 0.1), 1.3)
    u = body_direction(ri, rj, (-0.6, 0.8), 1.3)
    el = FollowerForce("f", combine([(1.0, p), (1.0, u)], stack=True), 2.5)
    check_force(el, 4, rng)
    K, _ = el.jacobians(np.zeros(4), np.zeros(4))
    assert np.abs(K - K.T).max() > 0.1  # non-conservative: K is not symmetric


@pytest.mark.parametrize("seed", range(3))
def test_distance_constraint(seed):
    rng = np.random.default_rng(seed)
    n = 4
    c = DistanceConstraint("d", free_point(2, 2) - free_point(0, 2), 1.3)
    q, qd, lam = rng.normal(size=n), rng.normal(size=n), rng.normal(size=1)
    assert_jac(c.jac(q), central(c.phi, q))
    # H(λ) = ∂(Φ_qᵀλ)/∂q
    assert_jac(c.hess(q, lam), central(lambda x: c.jac(x).T @ lam, q))
    # γ = −(Φ_q q̇)_q q̇
    gam = -central(lambda x: c.jac(x) @ qd, q) @ qd
    np.testing.assert_allclose(c.gamma(q, qd), gam, rtol=1e-7)


def test_linear_constraint_on_body_point():
    rng = np.random.default_rng(5)
    ri, rj = free_point(0, 2), free_point(2, 2)
    diff = free_point(4, 2) - body_point(ri, rj, (0.3, 0.2), 1.0)
    c = LinearConstraint("attach", diff, np.eye(2), np.zeros(2))
    q = rng.normal(size=6)
    assert_jac(c.jac(q), central(c.phi, q))
    assert np.all(c.hess(q, np.ones(2)) == 0)


def test_assembled_model_jacobians(cases_dir):
    """Model-level K, C, Φ_q and H on the four-bar at a perturbed, moving state."""
    import mbseig

    model = mbseig.load_case(cases_dir / "four_bar.toml")
    rng = np.random.default_rng(2)
    q = model.q_init + 0.01 * rng.normal(size=model.n)
    qd = rng.normal(size=model.n)
    lam = rng.normal(size=model.n_constraints)
    K, C = model.force_jacobians(q, qd)
    fs = np.abs(model.generalized_force(q, qd)).max()
    assert_jac(K.toarray(), -central(lambda x: model.generalized_force(x, qd), q), fs)
    assert_jac(C.toarray(), -central(lambda v: model.generalized_force(q, v), qd), fs)
    assert_jac(model.phi_q(q).toarray(), central(model.phi, q))
    assert_jac(model.constraint_hessian(q, lam).toarray(),
               central(lambda x: model.phi_q(x).T @ lam, q))
