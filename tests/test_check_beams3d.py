"""`mbseig check` on the bundled 3-D beam cases, at small meshes (the bundled 24-element runs
are timed in benchmarks/check_beams3d.py): the stiff model integrated in tangent coordinates of
its constraints (mbseig.check.tangent) keeps them to rounding, proves the right bending mode
and refutes a wrong linearization."""

from dataclasses import replace

import numpy as np
import pytest
from conftest import CASES

from mbseig.check.dynamics import ForwardDynamics
from mbseig.check.modes import check_modes
from mbseig.check.tangent import TangentCoordinates
from mbseig.modal import modes
from mbseig.statics import solved
from mbseig.studies import analyze

# 2 elements, 1 period, at ode_rtol 1e-4: a few seconds per check
SHORT = {"indices": [1], "periods": 1.0, "ode_rtol": 1e-4}


def _oblique(n=2):
    return analyze(CASES / "cantilever_3d_oblique.toml", params={"n": n})


def test_tangent_coordinates_keep_the_constraints_and_their_jacobian_is_exact():
    """Lifted states satisfy Φ = 0 to 1e-14 (scaled residual) and Φ_q q̇ = 0 to 1e-14 at a
    perturbation of 1e-3 of the length; the Newton matrix ∂(ẋ, ẍ)/∂(x, ẋ) at q₀ equals central
    differences of the tangent right-hand side (step 1e-9: agreement 1e-6 relative)."""
    a = _oblique()
    model = solved(a.model, a.eq)
    dyn = ForwardDynamics(model, a.linear.q0)
    tc = TangentCoordinates(dyn)
    rng = np.random.default_rng(2)
    k = tc.k
    x, xd = 1e-3 * rng.standard_normal(k), rng.standard_normal(k)
    u, v, res, _ = tc.lift(x, xd)
    q = dyn.q0 + u
    assert res <= 1e-14
    assert np.max(np.abs(model.phi(q)) / dyn.cscale) <= 1e-14
    assert np.max(np.abs(model.phi_q(q) @ v)) <= 1e-14 * np.abs(v).max()
    assert np.allclose(tc.N.T @ u, x, rtol=0, atol=1e-15)
    J = tc.jacobian()
    for part in (slice(0, k), slice(k, 2 * k)):
        dy = np.zeros(2 * k)
        dy[part] = 1e-9 * rng.standard_normal(k)
        fd = (tc.rhs(0.0, dy) - tc.rhs(0.0, -dy)) / 2
        assert np.abs(fd - J @ dy).max() <= 1e-6 * np.abs(J @ dy).max()


@pytest.mark.parametrize("method, integrator", [("DOP853", "exponential"), ("Radau", "Radau")])
def test_oblique_cantilever_mode_passes_and_a_wrong_stiffness_fails(method, integrator):
    """Mode 1 of cases/cantilever_3d_oblique.toml at 2 elements passes (reference: the nonlinear
    simulation itself: ω within 1e-5 of the prediction, δ of this undamped mode to the run's
    resolution); the prediction is the closed-form cantilever frequency 1.8751² √(E Iz/(ρ A L⁴))
    to the discretization error of 2 elements (< 1e-3, order h⁴).  The same model checked
    against a linearization whose stiffness is 10 % high (ω off by ~5 %) fails.  Both the
    default integrator of a stiff model (exponential Adams) and Radau."""
    a = _oblique()
    E, b, h, rho = 2.1e11, 0.02, 0.03, 7850.0
    w_exact = 1.8751040687119611**2 * np.sqrt(E * h * b**3 / 12 / (rho * b * h))
    assert abs(a.modes.omega_n[0] / w_exact - 1) < 1e-3
    res = check_modes(a.model, a.eq, a.linear, a.modes, method=method, **SHORT)
    m = res.modes[0]
    assert res.passed and res.integrator == integrator
    assert abs(m.measured_omega / m.predicted_omega - 1) < 1e-5
    assert m.constraint_drift <= 1e-13  # tangent coordinates: no drift, nothing projected
    wrong_lin = replace(a.linear, Q=1.1 * np.asarray(a.linear.Q))
    wrong = modes(wrong_lin)
    assert abs(wrong.omega_n[0] / a.modes.omega_n[0] - 1) > 0.04
    bad = check_modes(a.model, a.eq, wrong_lin, wrong, method=method, **SHORT)
    assert not bad.passed and bad.modes[0].rel_error_omega > 10 * 1e-3  # omega_rtol 1e-3


def test_quartic_shaft_is_checked_as_a_stiff_model(tmp_path):
    """The spinning Timoshenko shaft meshed with 2 quartic elements (constant mass, no
    configuration-dependent mass): the check recognizes its stiff axial and shear modes and
    integrates in tangent coordinates (exponential Adams); the first whirl mode passes (ω within
    1e-5 of the prediction, as above) with no constraint drift."""
    text = (CASES / "spinning_shaft_rayleigh.toml").read_text().replace(
        "shear_coefficient = 1e12\n", "").replace(
        'elements = "n"', 'elements = "n"\nelement = "quartic"')
    path = tmp_path / "quartic_shaft.toml"
    path.write_text(text)
    a = analyze(path, params={"n": 2})
    assert ForwardDynamics(a.model, a.eq.q).stiff
    res = check_modes(a.model, a.eq, a.linear, a.modes, **SHORT)
    m = res.modes[0]
    assert res.passed and res.integrator == "exponential"
    assert abs(m.measured_omega / m.predicted_omega - 1) < 1e-5
    assert m.constraint_drift <= 1e-13


def test_a_singular_solve_inside_the_integrator_is_a_simulation_error(monkeypatch):
    """Where the explicit integration reaches a state whose mass–constraint matrix is singular,
    the check raises SimulationError naming the file, the integrator and the interval (a
    one-line error at the command line), not numpy's LinAlgError (forced here by a failing
    solve)."""
    from mbseig.check import dynamics as D
    from mbseig.errors import SimulationError

    a = analyze(CASES / "pendulum.toml")

    def singular(self, q, qd):
        raise np.linalg.LinAlgError("Singular matrix")

    monkeypatch.setattr(D.ForwardDynamics, "acceleration", singular)
    with pytest.raises(SimulationError, match="mass-constraint matrix .* was singular") as e:
        check_modes(a.model, a.eq, a.linear, a.modes, indices=[1], periods=1.0)
    assert "pendulum.toml" in str(e.value) and "(DOP853)" in str(e.value)
