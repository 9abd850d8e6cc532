"""Four-bar linkage against an independent one-degree-of-freedom reduction.

The reduction uses only the crank angle θ and closed-form loop closure, not natural coordinates:

    B = a (cos θ, sin θ);  C from |C − B| = b, |C − D| = c (elbow-up, the larger y)
    C' and C'' from differentiating the two closure equations (2×2 linear solves)
    V(θ) = ½ k (θ − θ0)² + g Σ m_i y_Gi(θ),   m(θ) = Σ m_i |G_i'|² + I_i φ_i'²
    equilibrium V'(θ*) = 0 (Newton on V' with V''),   ω² = V''(θ*) / m(θ*)

All derivatives are analytic, so the reference is exact to rounding; tolerance 1e-10 relative
(the issue's requirement), with and without gravity.
"""

import numpy as np
import pytest
from conftest import CASES

from mbseig.studies import analyze

A_LEN, B_LEN, C_LEN = 0.3, 1.0, 0.8
MASS = (1.0, 2.0, 1.5)  # crank, coupler, rocker
INERTIA = tuple(m * L**2 / 12 for m, L in zip(MASS, (A_LEN, B_LEN, C_LEN), strict=True))
K_SPRING, THETA0 = 50.0, np.radians(60.0)
D = np.array([1.0, 0.0])
J = np.array([[0.0, -1.0], [1.0, 0.0]])


def closure(theta):
    """Positions and first and second θ-derivatives of B and C."""
    B = A_LEN * np.array([np.cos(theta), np.sin(theta)])
    B1 = A_LEN * np.array([-np.sin(theta), np.cos(theta)])
    B2 = -B
    d = np.linalg.norm(D - B)
    a = (B_LEN**2 - C_LEN**2 + d**2) / (2 * d)
    h = np.sqrt(B_LEN**2 - a**2)
    e = (D - B) / d
    cands = [B + a * e + s * h * (J @ e) for s in (1, -1)]
    C = max(cands, key=lambda p: p[1])  # elbow-up
    # (C − B)·(C' − B') = 0,  (C − D)·C' = 0
    G = np.array([C - B, C - D])
    C1 = np.linalg.solve(G, np.array([(C - B) @ B1, 0.0]))
    # (C' − B')·(C' − B') + (C − B)·(C'' − B'') = 0,  C'·C' + (C − D)·C'' = 0
    C2 = np.linalg.solve(G, np.array([(C - B) @ B2 - (C1 - B1) @ (C1 - B1), -(C1 @ C1)]))
    return B, B1, B2, C, C1, C2


def angle_rate(u, u1):
    return (u[0] * u1[1] - u[1] * u1[0]) / (u @ u)


def angle_rate2(u, u1, u2):
    r2 = u @ u
    cross = u[0] * u1[1] - u[1] * u1[0]
    return (u[0] * u2[1] - u[1] * u2[0]) / r2 - 2 * cross * (u @ u1) / r2**2


def reduced(theta, g):
    """V'(θ), V''(θ), m(θ) of the 1-DOF model."""
    B, B1, B2, C, C1, C2 = closure(theta)
    G = [(B / 2, B1 / 2, B2 / 2), ((B + C) / 2, (B1 + C1) / 2, (B2 + C2) / 2),
         ((D + C) / 2, C1 / 2, C2 / 2)]
    phi1 = [1.0, angle_rate(C - B, C1 - B1), angle_rate(C - D, C1)]
    dV = (K_SPRING * (theta - THETA0)
          + g * sum(m * Gk[1][1] for m, Gk in zip(MASS, G, strict=True)))
    d2V = K_SPRING + g * sum(m * Gk[2][1] for m, Gk in zip(MASS, G, strict=True))
    m_eff = (sum(m * Gk[1] @ Gk[1] for m, Gk in zip(MASS, G, strict=True))
             + sum(inertia * p**2 for inertia, p in zip(INERTIA, phi1, strict=True)))
    return dV, d2V, m_eff


def reference(g):
    theta = THETA0
    for _ in range(50):
        dV, d2V, _ = reduced(theta, g)
        step = dV / d2V
        theta -= step
        if abs(step) < 1e-15:
            break
    _, d2V, m_eff = reduced(theta, g)
    return theta, np.sqrt(d2V / m_eff)


def test_angle_rate2_matches_difference():
    """Self-check of the reference's own second derivative (central difference, 1e-6)."""
    th = 1.0
    h = 1e-5
    B, B1, B2, C, C1, C2 = closure(th)
    num = (angle_rate(*[closure(th + h)[i] - closure(th + h)[j] for i, j in ((3, 0), (4, 1))])
           - angle_rate(*[closure(th - h)[i] - closure(th - h)[j]
                          for i, j in ((3, 0), (4, 1))])) / (2 * h)
    assert angle_rate2(C - B, C1 - B1, C2 - B2) == pytest.approx(num, rel=1e-6)


@pytest.mark.parametrize("g", [9.81, 0.0])
def test_four_bar_matches_one_dof_reduction(g):
    theta_ref, omega_ref = reference(g)
    a = analyze(CASES / "four_bar.toml", params={"g": g})
    B = a.model.points["B"](a.eq.q)
    assert np.arctan2(B[1], B[0]) == pytest.approx(theta_ref, abs=1e-12)
    assert a.linear.dof == 1
    assert a.modes.omega_n[0] == pytest.approx(omega_ref, rel=1e-10)
    assert a.modes.verdict == "critical"


def test_gravity_shifts_the_four_bar():
    """The reference itself shows the load matters (else the comparison above proves little)."""
    assert abs(reference(9.81)[1] / reference(0.0)[1] - 1) > 0.005
