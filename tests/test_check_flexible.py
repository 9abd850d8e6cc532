"""`mbseig check` on co-rotational beams (configuration-dependent mass, stiff axial modes):
the nonlinear simulation (M(q), its velocity terms, Radau) proves the right linearization of a
preloaded column and refutes one without its geometric stiffness."""

from dataclasses import replace

import numpy as np
from conftest import write_case

import mbseig
from mbseig.check.modes import check_modes
from mbseig.linear import linearize
from mbseig.modal import modes
from mbseig.statics import equilibrium

# Steel strip 1 m × 20 mm × 10 mm, clamped–free, compressed by P = 430 N at the tip: half the
# Euler load π²EI/(4L²) = 863.6 N, so the geometric stiffness lowers the first bending
# frequency from 52.4 rad/s (P = 0) to 37.9 rad/s.
COLUMN = """
schema_version = 1
dimension = 2
[[points]]
name = "A"
position = [0.0, 0.0]
fixed = true
[[points]]
name = "B"
position = [1.0, 0.0]
[[beams]]
name = "beam"
points = ["A", "B"]
E = 2.1e11
rho = 7850.0
section = { shape = "rectangle", b = 0.02, h = 0.01 }
elements = 2
ends = ["clamped", "free"]
[[forces]]
type = "force"
point = "B"
vector = [-430.0, 0.0]
"""
FAST = {"indices": [1], "periods": 1.0, "ode_rtol": 1e-4}  # one period: 3 s; ω to ~1e-8 here


def test_geometric_stiffness_is_proved_and_a_wrong_one_fails(tmp_path):
    model = mbseig.load_case(write_case(tmp_path, COLUMN))
    eq = equilibrium(model)
    lin = linearize(model, eq)
    right = modes(lin)
    # Reference: the nonlinear simulation itself (an independent method); its ω within
    # omega_rtol = 1e-3 of the prediction, and the preload visibly at work (ω below P = 0's).
    res = check_modes(model, eq, lin, right, **FAST)
    assert res.passed and res.modes[0].rel_error_omega < 1e-5  # ode_rtol 1e-4: ~1e-6 reached
    assert res.modes[0].measured_omega < 0.8 * 52.4
    # Corrupted: the geometric part of the tangent, K(q_eq) − K(q_unloaded), taken out.
    _check_fails_without_geometric_stiffness(model, eq, lin, right)


# The same strip in 3-D along the oblique axis (1, 2, 2)/3, its section's y axis the
# orientation [0, 1, -1]: the compressive tip load of half the Euler load about the weak axis
# lowers the weak-plane bending frequency from 52.4 rad/s to 37.9 rad/s (as in 2-D).
COLUMN_3D = """
schema_version = 1
dimension = 3
[[points]]
name = "A"
position = [0.0, 0.0, 0.0]
fixed = true
[[points]]
name = "B"
position = [0.3333333333333333, 0.6666666666666666, 0.6666666666666666]
[[beams]]
name = "beam"
points = ["A", "B"]
E = 2.1e11
nu = 0.3
rho = 7850.0
section = { shape = "rectangle", b = 0.02, h = 0.01 }
orientation = [0.0, 1.0, -1.0]
theory = "euler-bernoulli"
elements = 2
ends = ["clamped", "free"]
[[forces]]
type = "force"
point = "B"
vector = [-143.33333333333334, -286.6666666666667, -286.6666666666667]
"""


def _column_3d(tmp_path):
    model = mbseig.load_case(write_case(tmp_path, COLUMN_3D))
    eq = equilibrium(model)
    return model, eq, linearize(model, eq)


def test_3d_geometric_stiffness_is_proved_and_a_wrong_one_fails(tmp_path):
    """3-D co-rotational beam: the weak-plane bending mode of the preloaded column passes
    (reference: the nonlinear simulation itself; ω to omega_rtol = 1e-3, reached ~1e-7) and the
    linearization without the geometric stiffness K(q_eq) − K(q_unloaded) fails it."""
    model, eq, lin = _column_3d(tmp_path)
    right = modes(lin)
    assert 0.6 * 52.4 < right.omega_n[0] < 0.8 * 52.4  # the preload at work (2 elements)
    res = check_modes(model, eq, lin, right, **FAST)
    assert res.passed and res.integrator == "exponential" and res.modes[0].rel_error_omega < 1e-5
    _check_fails_without_geometric_stiffness(model, eq, lin, right)


def test_3d_velocity_terms_and_newton_matrix_are_exact(tmp_path):
    """The closed-form velocity terms h = Ṁq̇ − ½∂(q̇ᵀMq̇)/∂q of each 3-D element against central
    differences of its own mass(q) (step 1e-6: agreement to 1e-7 relative), and the exact
    Newton matrix ∂(rhs)/∂y at the equilibrium against central differences of the right-hand
    side along directions tangent to the constraints (1e-6)."""
    from mbseig.check.dynamics import ForwardDynamics
    from mbseig.numerics import null_space_basis

    model, eq, _ = _column_3d(tmp_path)
    rng = np.random.default_rng(3)
    q = eq.q + 1e-2 * rng.standard_normal(model.n)
    qd = rng.standard_normal(model.n)
    h = 1e-6
    for el, _ in model.mass_elements:
        idx, v = el.idx, qd[el.idx]
        dq = np.zeros(model.n)
        dq[idx] = v
        ref = (el.mass(q + h * dq) - el.mass(q - h * dq)) @ v / (2 * h)
        for k, j in enumerate(idx):
            e = np.zeros(model.n)
            e[j] = h
            ref[k] -= v @ (el.mass(q + e) - el.mass(q - e)) @ v / (4 * h)
        got = el.velocity_terms(q, qd)
        assert np.abs(got - ref).max() <= 1e-7 * np.abs(ref).max()
    dyn = ForwardDynamics(model, eq.q)
    J = dyn.state_jacobian()
    N = null_space_basis(dyn.phi_q(eq.q), model.n, 1e-10)[0]
    n = model.n
    for _ in range(2):
        dy = np.concatenate([N @ rng.standard_normal(N.shape[1]),
                             N @ rng.standard_normal(N.shape[1])]) * 1e-7
        fd = (dyn.rhs(0.0, dy) - dyn.rhs(0.0, -dy)) / 2
        assert np.abs(fd - J @ dy).max() <= 1e-6 * np.abs(J @ dy).max()
    assert J.shape == (2 * n, 2 * n)


def _check_fails_without_geometric_stiffness(model, eq, lin, right):
    """The linearization with the geometric part of the tangent, K(q_eq) − K(q_unloaded), taken
    out: its frequency is off by more than 30 %, and the check fails it (error above
    10 × omega_rtol)."""
    N = np.asarray(lin.N)
    dK = (model.force_jacobians(eq.q)[0] - model.force_jacobians(model.q_init)[0]).toarray()
    wrong_lin = replace(lin, Q=np.asarray(lin.Q) - N.T @ dK @ N)
    wrong = modes(wrong_lin)
    assert abs(wrong.omega_n[0] / right.omega_n[0] - 1) > 0.3
    bad = check_modes(model, eq, wrong_lin, wrong, **FAST)
    assert not bad.passed and bad.modes[0].rel_error_omega > 10 * 1e-3
