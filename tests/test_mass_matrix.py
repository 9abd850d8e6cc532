"""Planar body mass matrix against the kinetic energy ½ m v_G² + ½ I_G ω² (DESIGN §2).

Independent reference: rigid-body kinematics. For basic points r_i, r_j with velocities, the body
rotates at ω = (u × u̇)/|u|² (u = r_j − r_i, constant length), and the centre of mass at local
(x̄_G, ȳ_G) moves with v_G = ṙ_i + ω × (R_local ρ_G). Tolerance 1e-12 relative (rounding only).
"""

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from mbseig.model.affine import Affine
from mbseig.model.elements import body_mass_matrix, body_point

finite = st.floats(-2.0, 2.0, allow_nan=False)


@settings(max_examples=60, deadline=None)
@given(
    mass=st.floats(0.01, 10.0), inertia=st.floats(0.0, 1.0), xg=finite, yg=finite,
    angle=st.floats(-np.pi, np.pi), L=st.floats(0.1, 3.0),
    vi=st.tuples(finite, finite), omega=finite,
)
def test_kinetic_energy(mass, inertia, xg, yg, angle, L, vi, omega):
    ri = np.array([0.3, -0.1])
    e = np.array([np.cos(angle), np.sin(angle)])
    rj = ri + L * e
    vi = np.array(vi)
    J = np.array([[0.0, -1.0], [1.0, 0.0]])
    vj = vi + omega * (J @ (rj - ri))  # rigid motion: rotation at rate omega
    M = body_mass_matrix(mass, inertia, (xg, yg), L)
    qd = np.concatenate([vi, vj])
    T_matrix = 0.5 * qd @ M @ qd
    rho = xg * e + yg * (J @ e)  # G relative to point i
    vG = vi + omega * (J @ rho)
    T_exact = 0.5 * mass * vG @ vG + 0.5 * inertia * omega**2
    assert abs(T_matrix - T_exact) <= 1e-12 * max(1.0, abs(T_exact))
    np.testing.assert_allclose(M, M.T, atol=1e-15)


def test_body_point_map():
    """r_P = C q_b reproduces the rigid placement of a local point (closed form)."""
    ri, rj = np.array([1.0, 2.0]), np.array([1.0 + 0.6, 2.0 + 0.8])  # L = 1, e = (0.6, 0.8)
    P = body_point(Affine.constant(ri), Affine.constant(rj), (0.5, 0.25), 1.0)
    expected = ri + 0.5 * np.array([0.6, 0.8]) + 0.25 * np.array([-0.8, 0.6])
    np.testing.assert_allclose(P(np.zeros(0)), expected, rtol=1e-15)
