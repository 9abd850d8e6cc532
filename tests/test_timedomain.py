"""Time-domain cross-check (`mbseig check`, mbseig.timedomain): predicted modes against
simulations of the nonlinear model.

References: closed forms named per test (pendulum ω = √(g/l); double pendulum ω² = (g/l)(2 ∓ √2);
damped chain from the case's [expected] table; inverted pendulum s = +√(g/l); Ziegler's flutter
eigenvalues from 2w² − (7 − 2p)w + 1 = 0, see cases/ziegler_pendulum.toml).  Tolerances are the
issue's: undamped |δ| ≤ 1e-5·ω over ≥ 20 periods and ω within 1e-4; damped, loaded and unstable
cases within 1 %.
"""

import json
import math

import numpy as np
import pytest
from conftest import CASES, write_case
from expected import expected_eigenvalues

import mbseig
from mbseig.check import check_modes
from mbseig.cli import main
from mbseig.studies import analyze

G = 9.81


def run_check(path, params=None, config=None, **kw):
    a = analyze(path, params=params, config=config)
    return a, check_modes(a.model, a.eq, a.linear, a.modes, **kw)


# ---- undamped: the integrator and the projection add no damping -------------------------------
def test_pendulum_undamped_over_20_periods():
    a, r = run_check(CASES / "pendulum.toml")
    (m,) = r.modes
    w = math.sqrt(G / 1.0)  # closed form √(g/l)
    assert m.periods >= 20
    assert abs(m.measured_delta) <= 1e-5 * w
    assert abs(m.measured_omega - w) <= 1e-4 * w
    assert m.passed and r.passed
    # the integrator's own contribution: measured 3e-12·ω with DOP853 at rtol 1e-10, i.e. far
    # below the check's 1e-5; asserted here with three orders of margin to the tolerance
    assert abs(m.measured_delta) <= 1e-8 * w
    # constraint drift (|Φ|/L²) stays far below the perturbation (amplitude 1e-4 of the length)
    assert m.constraint_drift <= 1e-12


def test_double_pendulum_undamped_over_20_periods():
    a, r = run_check(CASES / "double_pendulum.toml")
    w = np.sqrt(G * np.array([2 - math.sqrt(2), 2 + math.sqrt(2)]))  # closed form, l = 1
    assert len(r.modes) == 2
    for m, wk in zip(r.modes, w, strict=True):
        assert m.periods >= 20
        assert abs(m.measured_delta) <= 1e-5 * wk
        assert abs(m.measured_omega - wk) <= 1e-4 * wk
        assert m.passed
        assert m.constraint_drift <= 1e-12


def test_integrator_neutral_over_long_run():
    """100 periods of the undamped pendulum: the apparent δ stays below 1e-8·ω (Radau, slower,
    over 5 periods at the same tolerance too), so the integrator cannot account for a δ at the
    check's 1e-5 level (measured with DOP853: 3.0e-12·ω)."""
    for method in ("DOP853", "Radau"):
        _, r = run_check(CASES / "pendulum.toml", periods=100 if method == "DOP853" else 5,
                         method=method)
        m = r.modes[0]
        assert abs(m.measured_delta) <= 1e-8 * abs(m.eigenvalue), method


# ---- damped and loaded -------------------------------------------------------------------------
@pytest.fixture(scope="module")
def chain10():
    return analyze(CASES / "chain_damped.toml", params={"n": 10})


@pytest.mark.parametrize("k", range(1, 11))
def test_damped_chain_every_mode_within_1_percent(chain10, k):
    a = chain10
    r = check_modes(a.model, a.eq, a.linear, a.modes, indices=[k])
    (m,) = r.modes
    s = expected_eigenvalues(a.model.expected, a.model.parameters)  # closed form (case file)
    s = s[np.argmin(np.abs(s - a.modes.eigenvalues[k - 1]))]
    assert m.passed
    assert abs(m.measured_delta - m.predicted_delta) <= 1e-2 * m.predicted_delta
    assert abs(m.measured_omega - m.predicted_omega) <= 1e-2 * m.predicted_omega
    assert m.measured_delta == pytest.approx(-s.real, rel=1e-2)
    assert m.measured_omega == pytest.approx(s.imag, rel=1e-2)


def test_loaded_four_bar_within_1_percent():
    a, r = run_check(CASES / "four_bar.toml", delta_rtol=1e-2, omega_rtol=1e-2)
    assert len(r.modes) == 1 and r.passed
    m = r.modes[0]
    # undamped: δ judged against ω (the check's zero_delta_tol), ω relative to the prediction
    assert abs(m.measured_delta) <= 1e-5 * m.predicted_omega
    assert abs(m.measured_omega - m.predicted_omega) <= 1e-2 * m.predicted_omega


# ---- unstable ----------------------------------------------------------------------------------
def test_inverted_pendulum_divergence_rate():
    a, r = run_check(CASES / "pendulum.toml", params={"g": -G})
    sigma = math.sqrt(G / 1.0)  # closed form: s = ±√(g/l) for the inverted pendulum
    div = [m for m in r.modes if m.kind == "divergence"]
    assert len(div) == 1 and r.passed
    assert -div[0].measured_delta == pytest.approx(sigma, rel=1e-2)
    assert div[0].measured_delta == pytest.approx(div[0].predicted_delta, rel=1e-2)


def ziegler_eigenvalue(p, k=1.0, m=1.0, length=1.0):
    """Flutter eigenvalue (Re s > 0) of Ziegler's pendulum past p_cr: w = s²·(−m l²/k) solves
    2w² − (7 − 2p)w + 1 = 0 (cases/ziegler_pendulum.toml)."""
    w = (7 - 2 * p + np.sqrt(complex((7 - 2 * p) ** 2 - 8))) / 4
    s = np.sqrt(-w * k / (m * length * length))
    return complex(abs(s.real), abs(s.imag))


def test_ziegler_flutter_growth_rate():
    a, r = run_check(CASES / "ziegler_pendulum.toml", config="flutter")
    p = a.model.parameters["p"]
    assert p > 3.5 - math.sqrt(2)
    s = ziegler_eigenvalue(p)
    flutter = [m for m in r.modes if m.kind == "flutter"]
    assert len(flutter) == 1 and r.passed
    m = flutter[0]
    assert -m.measured_delta == pytest.approx(s.real, rel=1e-2)
    assert m.measured_delta == pytest.approx(m.predicted_delta, rel=1e-2)
    assert m.measured_omega == pytest.approx(s.imag, rel=1e-2)


def test_ziegler_flutter_load():
    """The case reproduces Ziegler's closed-form flutter load p_cr = 7/2 − √2 (±0.2 %)."""
    pcr = 3.5 - math.sqrt(2)
    below = analyze(CASES / "ziegler_pendulum.toml", params={"p": 0.998 * pcr}).modes
    above = analyze(CASES / "ziegler_pendulum.toml", params={"p": 1.002 * pcr}).modes
    assert below.verdict == "critical"
    assert above.verdict == "unstable" and "flutter" in above.kind


def test_linear_gyroscopic_case():
    """A linear case is integrated as given (M ẍ + P ẋ + Q x = 0).  Closed form (case file):
    s = ±i|ω₀ − Ω|, ±i(ω₀ + Ω); the gyroscopic P makes each mode a circular whirl in one sense,
    so the signed phase slope of η is checked, not only its size."""
    a, r = run_check(CASES / "rotating_mass.toml")
    p = a.model.parameters
    w = sorted([abs(p["omega0"] - p["Omega"]), p["omega0"] + p["Omega"]])
    assert r.passed and [m.index for m in r.modes] == [1, 2]
    for m, wk in zip(r.modes, w, strict=True):
        assert m.measured_omega == pytest.approx(wk, rel=1e-4)
        assert abs(m.measured_delta) <= 1e-5 * wk


# ---- a wrong linearization fails --------------------------------------------------------------
def test_wrong_linearization_fails_on_four_bar():
    a = analyze(CASES / "four_bar.toml")
    wrong = mbseig.linearize(a.model, a.eq, constraint_stiffness=False)
    md = mbseig.modes(wrong.M, wrong.P, wrong.Q, N=wrong.N)
    r = check_modes(a.model, a.eq, wrong, md)
    assert not r.passed and r.failed == [1]
    m = r.modes[0]
    assert not r.constraint_stiffness
    assert m.rel_error_omega > 1e-2  # fails even at the loose 1 % tolerance
    # what the simulation measures is the correct linearization's frequency
    assert m.measured_omega == pytest.approx(a.modes.omega_d[0], rel=1e-4)


# ---- skipped, massless, redundant -------------------------------------------------------------
def test_rigid_body_mode_skipped_and_probed():
    """A true rigid-body mode (free-free chain translation) is not fitted (reason given); the
    static probe finds no restoring force (exactly zero for a translation of linear springs)."""
    a, r = run_check(CASES / "chain_free_free.toml", params={"n": 3}, indices=[1, 2])
    assert a.modes.kind[0] == "rigid-body"
    m = r.modes[0]
    assert "rigid-body" in m.skipped and m.passed is True
    assert m.probe_omega <= 1e-9 * m.probe_reference
    assert r.modes[1].passed and r.passed
    out = r.to_dict()["modes"][0]
    assert out["measured"]["delta"] is None and out["skipped"] and out["probe"]["omega_eff"] >= 0


def test_wrong_linearization_fails_on_pendulum():
    """Without Σλ∇²Φ the pendulum's mode is predicted rigid-body (DESIGN §4); it is not fitted,
    but the static probe of the nonlinear model finds the restoring frequency √(g/l) (closed
    form, central differences of O(ε²) = 1e-8 accuracy, asserted to 1e-6) and the check fails."""
    for path, n in (("pendulum.toml", 1), ("double_pendulum.toml", 2)):
        a = analyze(CASES / path)
        wrong = mbseig.linearize(a.model, a.eq, constraint_stiffness=False)
        md = mbseig.modes(wrong.M, wrong.P, wrong.Q, N=wrong.N)
        assert md.kind == ["rigid-body"] * n
        r = check_modes(a.model, a.eq, wrong, md)
        assert not r.passed and r.failed == list(range(1, n + 1))
    a = analyze(CASES / "pendulum.toml")
    wrong = mbseig.linearize(a.model, a.eq, constraint_stiffness=False)
    r = check_modes(a.model, a.eq, wrong, mbseig.modes(wrong.M, wrong.P, wrong.Q, N=wrong.N))
    assert r.modes[0].probe_omega == pytest.approx(math.sqrt(G), rel=1e-6)


MASSLESS = """
schema_version = 1
title = "spring-mass pair, the second point massless"
source = "test"
dimension = 1
[[points]]
name = "W1"
position = [0.0]
fixed = true
[[points]]
name = "A"
position = [1.0]
[[points]]
name = "B"
position = [2.0]
[[points]]
name = "W2"
position = [3.0]
fixed = true
[[masses]]
point = "A"
mass = 1.0
[[forces]]
type = "spring"
points = ["W1", "A"]
stiffness = 1.0
[[forces]]
type = "spring"
points = ["A", "B"]
stiffness = 1.0
[[forces]]
type = "spring"
points = ["B", "W2"]
stiffness = 1.0
[expected]
source = "none"
"""


def test_massless_free_point_is_a_clear_error(tmp_path, capsys):
    path = write_case(tmp_path, MASSLESS)
    a = analyze(path)
    with pytest.raises(mbseig.SimulationError, match="massless free motion of B.x"):
        check_modes(a.model, a.eq, a.linear, a.modes)
    assert main(["check", str(path)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "B.x" in err[0] and str(path) in err[0]


TRIANGLE = (CASES / "pendulum.toml").read_text() + """
[[points]]
name = "H"
position = [0.3, -0.5]

[[joints]]
type = "distance"
points = ["O", "H"]

[[joints]]
type = "distance"
points = ["H", "P"]
"""


def test_massless_point_fixed_by_constraints(tmp_path):
    """A massless point carried by a rigid triangle: the index-1 system stays regular and the
    frequency is still √(g/l) (all mass at P)."""
    a, r = run_check(write_case(tmp_path, TRIANGLE))
    (m,) = r.modes
    assert m.passed and m.measured_omega == pytest.approx(math.sqrt(G), rel=1e-4)


def test_redundant_constraints(tmp_path):
    text = (CASES / "pendulum.toml").read_text() + (
        '\n[[joints]]\ntype = "distance"\nname = "rod twin"\npoints = ["O", "P"]\nlength = "l"\n')
    a, r = run_check(write_case(tmp_path, text))
    assert a.eq.n_redundant == 1
    assert r.passed and r.modes[0].measured_omega == pytest.approx(math.sqrt(G), rel=1e-4)


# ---- reactions ----------------------------------------------------------------------------------
def test_reactions_named_pendulum():
    _, r = run_check(CASES / "pendulum.toml", periods=2)
    (rod,) = r.reactions
    assert "rod" in rod["element"]
    # statics: the rod holds the bob's weight m g upward (m = 1)
    np.testing.assert_allclose(rod["forces"]["P"], [0.0, G], atol=1e-12)


# ---- command line -------------------------------------------------------------------------------
def test_cli_json_schema(capsys):
    assert main(["check", str(CASES / "double_pendulum.toml"), "--json", "--modes", "2"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["passed"] is True and len(out["modes"]) == 1
    m = out["modes"][0]
    assert m["index"] == 2
    assert {"index", "predicted", "measured", "rel_error", "passed", "tolerances"} <= set(m)
    assert set(m["predicted"]) == set(m["measured"]) == set(m["rel_error"]) == {"delta", "omega"}
    assert m["tolerances"] == {"delta_rtol": 1e-2, "omega_rtol": 1e-3, "zero_delta_tol": 1e-5}
    assert [x["element"] for x in out["reactions"]] == ["joints[0] 'rod1'", "joints[1] 'rod2'"]


def test_cli_exit_1_on_failure_and_table(capsys):
    # an impossible tolerance: the check must fail and say so
    code = main(["check", str(CASES / "pendulum.toml"), "--omega-rtol", "1e-14"])
    out = capsys.readouterr().out
    assert code == 1
    assert "FAIL" in out and "check: FAILED for mode(s) 1" in out
    assert "joints[0] 'rod'" in out  # reactions printed with element names


@pytest.mark.parametrize("extra, needle", [
    (["--modes", "3"], "--modes: mode numbers must lie in 1..1"),
    (["--modes", "x"], "--modes: mode list must be integers"),
    (["--amplitude", "-1"], "amplitude: must be a positive number"),
])
def test_cli_bad_options(capsys, extra, needle):
    assert main(["check", str(CASES / "pendulum.toml"), *extra]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and needle in err[0]


def test_cli_plot(tmp_path, capsys):
    assert main(["check", str(CASES / "pendulum.toml"), "--periods", "3",
                 "--plot", str(tmp_path / "plots")]) == 0
    png = tmp_path / "plots" / "pendulum_mode1.png"
    assert png.exists() and png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert f"wrote {png}" in capsys.readouterr().out


def test_cli_three_dof_device_reactions_and_actuator(capsys):
    """The 3-DOF finger exoskeleton: every mode passes, and the output names the joint reactions
    and the actuator effort found by inverse statics (the driver's record on the model)."""
    path = CASES / "hand_device.toml"
    assert main(["check", str(path)]) == 0
    out = capsys.readouterr().out
    assert "check: passed (3 simulated, 0 rigid-body probed, 0 skipped)" in out
    assert "joints[1] 'guide'" in out and "bodies[3] 'rod' (rigid length)" in out
    assert "actuator joints[2] 'MCP command': effort" in out
