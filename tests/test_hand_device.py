"""The finger exoskeleton case (cases/hand_device.toml, specification hand_device.md, clarified).

Reference values: the constraint count of the specification (10 coordinates, 7 constraints,
3 DOF in every configuration: C4 keeps the series spring), the definition of inverse statics
(MCP at equilibrium equals the commanded angle on the unloaded device), the held position
command of C4 (its free length is C1's), Newton's first law on the whole mechanism (independent
of the pin-reaction formula), the scaling rules of the specification, central differences for
the driver's derivatives, and for C4's flutter loads independent roots: the spectral abscissa of
the first-order state matrix (numpy eigvals) and the discriminant of the characteristic cubic of
M⁻¹Q (undamped).
"""

import math

import numpy as np
import pytest
from conftest import CASES

import mbseig
from mbseig.check import check_modes
from mbseig.errors import CaseError
from mbseig.statics.reactions import pin_reactions, posture, reactions, rom_flags
from mbseig.studies import analyze

CASE = CASES / "hand_device.toml"


@pytest.mark.parametrize("config, n_constraints, dof", [("C1", 7, 3), ("C2", 7, 3), ("C3", 7, 3),
                                                         ("C4", 7, 3)])
def test_coordinates_constraints_dof(config, n_constraints, dof):
    a = analyze(CASE, config=config)
    assert a.model.n == 10
    assert a.model.n_constraints == n_constraints
    assert a.eq.n_redundant == 0
    assert a.linear.dof == dof


@pytest.mark.parametrize("config, params, target", [("C1", {}, 45.0), ("C3", {}, 30.0),
                                                     ("C1", {"mcp_target": 70.0}, 70.0),
                                                     ("C4", {"f": 0.0}, 45.0)])
def test_mcp_equals_commanded_angle(config, params, target):
    """Inverse statics: the actuator free length puts the MCP at mcp_target on the unloaded
    device (tolerance 1e-9 deg: the secant stops at |driver effort| ≤ 1e-12 of the released
    effort)."""
    model = mbseig.load_case(CASE, config=config, **params)
    eq = mbseig.equilibrium(model)
    mcp = next(p for p in posture(model, eq.q) if p["name"] == "MCP")
    assert mcp["angle_deg"] == pytest.approx(target, abs=1e-9)
    drivers = eq.model.drivers  # inverse statics runs in the equilibrium stage, not at loading
    assert drivers and abs(drivers[0]["residual_effort"] if "residual_effort" in
                           drivers[0] else 0.0) <= 1e-12 * abs(drivers[0]["effort"])


def test_C4_holds_the_position_command():
    """C4 (hand_device.md, clarified): the actuator's free length stays at C1's inverse-statics
    value (bitwise: the command is resolved on the device without the follower load) for every
    f, the series spring stays in the load path (no distance joint: 3 DOF), and the posture
    moves with the load (MCP more than 1° from 45° at f = 1 N)."""
    eq1 = mbseig.equilibrium(mbseig.load_case(CASE, config="C1"))
    l0 = eq1.model.drivers[0]["sets"][0]["free_length"]
    for f in (0.0, 1.0, 2.0):
        eq = mbseig.equilibrium(mbseig.load_case(CASE, config="C4", f=f))
        rec = eq.model.drivers[0]
        assert rec["sets"][0]["free_length"] == l0
        assert rec["unloaded"] == ["forces[4] 'tendon load'"]
        mcp = next(p for p in posture(eq.model, eq.q) if p["name"] == "MCP")["angle_deg"]
        assert (abs(mcp - 45.0) > 1.0) == (f >= 1.0)
    assert not any("lock" in c.name for c in eq.model.constraints)


def test_C4_modes_up_to_the_range_of_motion_limit(capsys):
    """`mbseig modes` gives C4's equilibrium and modes at f = 2.4 N (the old model said
    "constraints are inconsistent" from 1.7 N on): exit 0, 3 modes, flutter (unstable), and the
    PIP flagged outside its range of motion (−0.6° < 0°)."""
    from mbseig.cli import main

    assert main(["modes", str(CASE), "--config", "C4", "--param", "f=2.4", "--json"]) == 0
    import json

    out = json.loads(capsys.readouterr().out)
    assert out["dof"] == 3 and len(out["modes"]) >= 3 and out["verdict"] == "unstable"
    eq = mbseig.equilibrium(mbseig.load_case(CASE, config="C4", f=2.4))
    assert rom_flags(eq.model, eq.q) == ["PIP"]


def _abscissa(f, scale):
    """max Re of the first-order state matrix at C4 (numpy eigvals: no QEP solver, tracking or
    boundary locator of mbseig involved)."""
    m = mbseig.load_case(CASE, config="C4", f=f, damping_scale=scale)
    lin = mbseig.linearize(m, mbseig.equilibrium(m))
    return float(np.max(np.linalg.eigvals(lin.state_matrix()).real))


def _undamped_discriminant(f):
    """Discriminant of the characteristic cubic of M⁻¹Q (s² = −μ): two real μ collide (flutter
    of the undamped C4) where it changes sign."""
    m = mbseig.load_case(CASE, config="C4", f=f, damping_scale=0.0)
    lin = mbseig.linearize(m, mbseig.equilibrium(m))
    a, b, c, d = np.poly(np.linalg.solve(lin.M, lin.Q)).real
    return 18 * a * b * c * d - 4 * b**3 * d + b * b * c * c - 4 * a * c**3 - 27 * a * a * d * d


def test_C4_sweep_every_point_and_the_flutter_loads():
    """`mbseig sweep` over f = 0 … 2.5 N on C4 (damping scales 1 and 0): no failed point (the
    old model lost 9 of 26), PIP flagged outside its range only past 2.35 N, and the flutter
    boundaries at the independent roots: the state-matrix abscissa (damped, 1e-8) and the cubic
    discriminant (undamped, 1e-8)."""
    from scipy.optimize import brentq

    from mbseig.studies.sweep import run_sweep

    values = np.linspace(0.0, 2.5, 6)
    res = run_sweep(CASE, [("f", values), ("damping_scale", np.array([1.0, 0.0]))],
                    config="C4", jobs=1, curves=False)
    for line in res.points:
        assert all(pt["error"] is None for pt in line)
        for f, pt in zip(values, line, strict=True):
            assert pt["out_of_range"] == (["PIP"] if f > 2.35 else [])
    damped = [b for b in res.boundaries if b["fixed"]["damping_scale"] == 1.0]
    undamped = [b for b in res.boundaries if b["fixed"]["damping_scale"] == 0.0]
    assert len(damped) == 1 and len(undamped) == 1
    f_damped = brentq(lambda f: _abscissa(f, 1.0), 1.5, 2.0, xtol=1e-13)
    f_undamped = brentq(_undamped_discriminant, 1.5, 1.75, xtol=1e-13)
    assert damped[0]["value"] == pytest.approx(f_damped, rel=1e-8)
    assert undamped[0]["value"] == pytest.approx(f_undamped, rel=1e-8)
    assert damped[0]["kind"] == undamped[0]["kind"] == "flutter"
    assert damped[0]["stability"] == undamped[0]["stability"] == "loss"


def test_global_force_balance():
    """Σ external forces on the whole device = 0 (tolerance 1e-12 N): ground at the MCP pin
    (from the phalanges' outboard statics) + guide normal force + actuator force on S + all
    weights.  The guide and actuator forces do not enter the pin formula, so this checks it."""
    model = mbseig.load_case(CASE, config="C1")
    eq = mbseig.equilibrium(model)
    rep = reactions(model, eq)
    R_mcp = np.array(next(p["force"] for p in rep["pins"] if p["name"] == "MCP"))
    guide = np.array(next(c["force"] for c in rep["constraints"] if "guide" in c["element"]))
    act = rep["actuator"][0]
    S, G = model.points["S"](eq.q), model.points["G"](eq.q)
    e = (S - G) / np.linalg.norm(S - G)
    F_act = -act["tension"] * e  # a tensioned actuator pulls S towards G
    g = np.array([0.0, -9.81])
    weights = (0.0155 + 0.00679 + 0.00391 + 0.003 + 0.010) * g
    total = R_mcp + guide + F_act + weights
    assert np.abs(total).max() < 1e-12


def test_distal_pins_closed_form_with_follower():
    """DIP pin: the distal phalanx carries only its weight and the follower force, so the force
    on it through C is −(m3 g − f (r_D − r_C)/L3) (closed form, 1e-12 N)."""
    f = 1.2
    model = mbseig.load_case(CASE, config="C4", f=f)
    eq = mbseig.equilibrium(model)
    dip = next(p for p in pin_reactions(model, eq) if p["name"] == "DIP")
    C, D = model.points["C"](eq.q), model.points["D"](eq.q)
    expected = -(0.00391 * np.array([0.0, -9.81]) - f * (D - C) / np.linalg.norm(D - C))
    np.testing.assert_allclose(dip["force"], expected, atol=1e-12)


def test_hand_length_scaling():
    """Lengths ∝ L, masses ∝ L³, inertias ∝ L⁵ relative to 0.19 m (specification)."""
    r = 0.21 / 0.19
    model = mbseig.load_case(CASE, hand_length=0.21)
    p = model.parameters
    assert model.bodies["proximal"]["length"] == pytest.approx(0.245 * 0.21, rel=1e-15)
    assert model.bodies["distal"]["mass"] == pytest.approx(0.00391 * r**3, rel=1e-15)
    assert p["I2"] == pytest.approx(4.51e-7 * r**5, rel=1e-15)


def test_rom_flags_under_large_follower_force():
    """At f = 2.5 N the follower force straightens the PIP past 0 deg (outside 0…100)."""
    model = mbseig.load_case(CASE, config="C4", f=2.5)
    eq = mbseig.equilibrium(model)
    pip = next(x for x in posture(model, eq.q) if x["name"] == "PIP")
    assert pip["angle_deg"] < 0 and rom_flags(model, eq.q) == ["PIP"]
    model0 = mbseig.load_case(CASE, config="C4")
    assert rom_flags(model0, mbseig.equilibrium(model0).q) == []


def test_constraint_stiffness_matters_in_C3():
    """C3 carries large constraint forces (|λ| > 100): dropping Σ λ ∇²Φ moves the lowest
    eigenvalue by more than 10 % (measured 79 %)."""
    model = mbseig.load_case(CASE, config="C3")
    eq = mbseig.equilibrium(model)
    s_with = mbseig.modes(*_mpq(mbseig.linearize(model, eq))).all_eigenvalues
    lin_wo = mbseig.linearize(model, eq, constraint_stiffness=False)
    s_wo = mbseig.modes(*_mpq(lin_wo)).all_eigenvalues
    assert np.abs(eq.lam).max() > 100
    d = [np.min(np.abs(s_wo - s)) / abs(s) for s in s_with]
    assert max(d) > 0.1


def _mpq(lin):
    return lin.M, lin.P, lin.Q


def test_C3_modes_pass_time_domain_check():
    """The nonlinear simulation (mbseig.check) confirms C3's modes computed with the
    constraint-force stiffness (tolerances of the check: δ 1e-2, ω 1e-3 relative)."""
    a = analyze(CASE, config="C3")
    res = check_modes(a.model, a.eq, a.linear, a.modes)
    assert res.passed and all(m.passed for m in res.modes)


def _driver_and_q():
    model = mbseig.load_case(CASE)
    from mbseig.model.driver import AngleDriver

    rng = np.random.default_rng(1)
    q = model.q_init + 1e-3 * rng.standard_normal(model.n)
    ang = model.report["angles"][1]["driver"]  # PIP: two free bodies
    return AngleDriver("test", ang.dirs, 0.3, ang.sense), q, rng


def test_angle_driver_derivatives_central_differences():
    """Φ_q, Σλ∇²Φ and γ of the angle driver against central differences (h = 1e-7; rtol 1e-6)."""
    d, q, rng = _driver_and_q()
    idx = d.idx
    h = 1e-7

    def phi_local(x):
        qq = q.copy()
        qq[idx] = x
        return d.phi(qq)[0]

    x0 = q[idx]
    grad = np.array([(phi_local(x0 + h * e) - phi_local(x0 - h * e)) / (2 * h)
                     for e in np.eye(idx.size)])
    np.testing.assert_allclose(d.jac(q)[0], grad, rtol=1e-6, atol=1e-6 * np.abs(grad).max())

    def jac_local(x):
        qq = q.copy()
        qq[idx] = x
        return d.jac(qq)[0]

    hess = np.array([(jac_local(x0 + h * e) - jac_local(x0 - h * e)) / (2 * h)
                     for e in np.eye(idx.size)])
    lam = np.array([0.7])
    np.testing.assert_allclose(d.hess(q, lam), 0.7 * hess, rtol=1e-5,
                               atol=1e-5 * np.abs(hess).max())
    qd = np.zeros_like(q)
    qd[idx] = rng.standard_normal(idx.size)
    assert d.gamma(q, qd)[0] == pytest.approx(-(qd[idx] @ hess @ qd[idx]), rel=1e-5)


def test_driver_naming_unknown_element_is_a_case_error(tmp_path):
    text = CASE.read_text().replace('sets = ["actuator"]', 'sets = ["nope"]')
    p = tmp_path / "bad.toml"
    p.write_text(text)
    with pytest.raises(CaseError, match="sets unknown element 'nope'"):
        mbseig.load_case(p)


def test_negative_damping_needs_active_flag(tmp_path):
    """A passive spring_damper must dissipate; the actuator is marked active so c_a < 0 is
    allowed."""
    assert mbseig.load_case(CASE, config="C2", c_a=-5.0).parameters["c_a"] == -5.0
    text = CASE.read_text().replace("active = true ", "active = false ")
    p = tmp_path / "passive.toml"
    p.write_text(text)
    with pytest.raises(CaseError, match="damping must not be negative"):
        mbseig.load_case(p, c_a=-5.0)
    table = reactions(mbseig.load_case(CASE), mbseig.equilibrium(mbseig.load_case(CASE)))
    assert math.isfinite(table["actuator"][0]["tension"])
