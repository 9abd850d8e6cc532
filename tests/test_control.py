"""Control-ready linear models (issue 12, control half): named inputs and outputs, B, C, D,
``mbseig frf``, the continuous null-space basis, natural and damped frequencies, eigenvalue
sensitivities and modal energy.

Reference values and their sources (each test names its own):
- DC gain: finite-difference statics of the *nonlinear* model under a small extra actuator force
  (an input u on a spring is, exactly, a shift of its free length by −u/k);
- zeros: the poles of the device with the MCP angle held by an added angle constraint (the zero
  dynamics, computed by the ordinary equilibrium → linearize → eigen path);
- frequency response: python-control's own evaluation of the StateSpace, and a time-domain step
  of the nonlinear equations (mbseig.check.dynamics) at small amplitude;
- reaction outputs: central differences of the multipliers of the nonlinear index-1 solve;
- sensitivities: central differences of the eigenvalues themselves (Richardson-extrapolated);
- energy: the pendulum's potential is all gravity (closed form), shares sum to 1 by definition
  and the kinetic parts are checked against the mass matrix's own quadratic form.
"""

import dataclasses
import io
import json
import math
import tomllib
from contextlib import redirect_stdout

import numpy as np
import pytest
from conftest import CASES

import mbseig
from mbseig import casefile
from mbseig.casefile import CaseSpec
from mbseig.cli import main
from mbseig.model.driver import AngleDriver
from mbseig.model.signals import output_value
from mbseig.statics import equilibrium
from mbseig.studies import analyze

CASE = CASES / "hand_device.toml"

IO_BLOCK = """
[[inputs]]
name = "actuator force"
element = "actuator"

[[inputs]]
name = "MCP torque"
bodies = ["ground", "proximal"]
sense = "cw"

[[outputs]]
name = "MCP angle"
quantity = "angle"
bodies = ["ground", "proximal"]
sense = "cw"

[[outputs]]
name = "actuator force"
quantity = "force"
element = "actuator"

[[outputs]]
name = "guide reaction"
quantity = "force"
element = "guide"
direction = [1.0, 0.0]

[[outputs]]
name = "slider velocity"
quantity = "velocity"
point = "S"
direction = [0.0, 1.0]
"""


@pytest.fixture(autouse=True, scope="module")
def _signal_tables():
    # [[inputs]] / [[outputs]] are top-level tables of the case format (DESIGN §8); until the
    # reader's list of top-level keys (mbseig/casefile/__init__.py, _TOP_KEYS) names them,
    # add them here (a no-op once it does)
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(casefile, "_TOP_KEYS", casefile._TOP_KEYS | {"inputs", "outputs"})
        yield


def _hand_text():
    text = CASE.read_text()
    return text if "[[inputs]]" in text else text + IO_BLOCK


@pytest.fixture(scope="module")
def hand_path(tmp_path_factory):
    path = tmp_path_factory.mktemp("hand") / "hand_device.toml"
    path.write_text(_hand_text())
    return path


def _spec(text, name="case"):
    return CaseSpec(tomllib.loads(text), name, f"{name}.toml")


def _cli(argv):
    buf = io.StringIO()
    with redirect_stdout(buf):
        code = main(argv)
    return code, buf.getvalue()


def _mcp_output(model):
    return next(o for o in model.outputs if o.name == "MCP angle")


# --------------------------------------------------------------------------------------------
# hand device: actuator force → MCP angle
# --------------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def c2_frf(hand_path):
    code, text = _cli(["frf", str(hand_path), "--config", "C2", "--input", "actuator force",
                       "--output", "MCP angle", "--hz", "0.5:200:40", "--json"])
    assert code == 0
    return json.loads(text)


def _solved(config):
    model = _spec(_hand_text(), "hand").build(config)
    eq = equilibrium(model)
    return eq.model, eq


def test_dc_gain_equals_finite_difference_statics(c2_frf):
    # reference: nonlinear statics with the actuator's free length shifted by ∓ε/k_a, which is
    # exactly an extra tension ±ε (f = k (l − l0) + u); central difference, ε = 1e-3 N: the
    # truncation error is O(ε²) ~ 1e-8 relative, far inside the 1e-6 asserted
    model, eq = _solved("C2")
    k = next(f for f in model.forces if f.name.endswith("'actuator'"))
    out = _mcp_output(model)
    eps = 1e-3

    def theta(u):
        forces = tuple(dataclasses.replace(f, free_length=f.free_length - u / f.stiffness)
                       if f is k else f for f in model.forces)
        m = dataclasses.replace(model, forces=forces, q_init=eq.q)
        e = equilibrium(m)
        return output_value(m, out, e.q, np.zeros(m.n))

    reference = (theta(eps) - theta(-eps)) / (2 * eps)
    assert c2_frf["dc_gain"] == pytest.approx(reference, rel=1e-6)
    # the lowest frequency of the response approaches it (0.5 Hz is far below the 10 Hz pole)
    assert c2_frf["response"][0][0] == pytest.approx(reference, rel=1e-2)


def test_zeros_are_the_poles_with_the_mcp_angle_held(c2_frf):
    # reference: the device with an added constraint holding the MCP angle at its equilibrium
    # value (zero dynamics), through the ordinary equilibrium → linearize → eigen path
    model, eq = _solved("C2")
    out = _mcp_output(model)
    held = AngleDriver("MCP held", out.dirs, output_value(model, out, eq.q, np.zeros(model.n)),
                       out.sense)
    m = dataclasses.replace(model, constraints=model.constraints + (held,), q_init=eq.q)
    e = equilibrium(m)
    lin = mbseig.linearize(m, e)
    assert lin.dof == 2
    poles = mbseig.solve_qep(lin.M, lin.P, lin.Q).eigenvalues
    zeros = np.array([complex(*z) for z in c2_frf["zeros"]])
    assert zeros.size == poles.size == 4
    # tolerance: both sides are backward-stable eigenvalue computations of well-conditioned
    # 2-DOF / Rosenbrock problems (κ ~ 1e2, η ~ 1e-16): 1e-9 relative, one to one
    for z in zeros:
        assert np.min(np.abs(poles - z)) <= 1e-9 * abs(z)
    for p in poles:
        assert np.min(np.abs(zeros - p)) <= 1e-9 * abs(p)


def test_poles_listed_in_full_and_equal_to_the_modes(c2_frf, hand_path):
    a = analyze(hand_path, config="C2")
    listed = a.modes.eigenvalues
    full = np.concatenate([listed, np.conj(listed[np.abs(listed.imag) > 0])])
    poles = np.array([complex(*p) for p in c2_frf["poles"]])
    assert poles.size == 2 * a.linear.dof
    np.testing.assert_allclose(np.sort_complex(poles), np.sort_complex(full), rtol=1e-12)


def test_response_matches_python_control(c2_frf, hand_path):
    control = pytest.importorskip("control")
    a = analyze(hand_path, config="C2")
    sys = a.linear.to_statespace()
    # the labels are the case's names, in the case's order
    assert list(sys.input_labels) == list(a.linear.input_names)
    assert list(sys.output_labels) == list(a.linear.output_names)
    assert {"actuator force", "MCP torque"} <= set(sys.input_labels)
    assert "MCP angle" in sys.output_labels
    f = np.array(c2_frf["freq_hz"])
    resp = np.array([complex(*z) for z in c2_frf["response"]])
    i = list(sys.input_labels).index("actuator force")
    j = list(sys.output_labels).index("MCP angle")
    ref = np.array([complex(sys(2j * np.pi * fk)[j, i]) for fk in f])
    # tolerance: two evaluations of one rational function (second-order solve vs. the
    # first-order state space): rounding only, 1e-10 relative
    np.testing.assert_allclose(resp, ref, rtol=1e-10)
    assert control.dcgain(sys[j, i]) == pytest.approx(c2_frf["dc_gain"], rel=1e-10)


def test_step_response_matches_the_nonlinear_model():
    # reference: the nonlinear constrained equations (mbseig.check.dynamics) driven by a small
    # step of actuator force through Model.generalized_force(q, q̇, u); the linear step response
    # must agree to O(u) relative (u = 1e-3 N moves the MCP ~4e-6 rad)
    control = pytest.importorskip("control")
    from mbseig.check.dynamics import simulate
    from mbseig.check.forced import ForcedDynamics

    model, eq = _solved("C1")
    u = 1e-3
    dyn = ForcedDynamics(model, eq.q, {"actuator force": u})
    t = np.linspace(0.0, 0.12, 121)
    sim = simulate(dyn, np.zeros(model.n), np.zeros(model.n), t, segment_samples=20,
                   rtol=1e-11, atol_position=1e-14, atol_velocity=1e-12)
    out = _mcp_output(model)
    theta0 = output_value(model, out, eq.q, np.zeros(model.n))
    y_nl = np.array([output_value(model, out, eq.q + sim.u[:, k], sim.v[:, k]) - theta0
                     for k in range(t.size)])
    lin = mbseig.linearize(model, eq)
    sys = lin.to_statespace()
    i = list(lin.input_names).index("actuator force")
    j = list(lin.output_names).index("MCP angle")
    y_lin = control.forced_response(sys[j, i], T=t, U=np.full(t.size, u)).outputs
    scale = np.max(np.abs(y_lin))
    assert scale > 1e-6
    assert np.max(np.abs(y_nl - y_lin)) <= 1e-3 * scale


def test_reaction_output_matches_multiplier_differences():
    # reference: δλ of the nonlinear index-1 solve (ForwardDynamics.acceleration) by central
    # differences along each reduced coordinate, velocity and input; ε = 1e-7 (relative
    # truncation ~1e-10; the comparison tolerance 1e-6 covers rounding ~1e-9)
    from mbseig.check.dynamics import ForwardDynamics

    model, eq = _solved("C1")
    lin = mbseig.linearize(model, eq)
    j = list(lin.output_names).index("guide reaction")
    out = model.outputs[j]
    n, d = model.n, lin.dof

    def y(dq, dv, u):
        class Forced(ForwardDynamics):
            def force(self, q, qd):
                return self.model.generalized_force(q, qd, {"actuator force": u})

        _, lam = Forced(model, eq.q).acceleration(eq.q + dq, dv)
        return output_value(model, out, eq.q + dq, dv, lam)

    eps = 1e-7
    scale = max(np.max(np.abs(lin.C[j])), 1.0)
    for k in range(d):
        dq = eps * lin.N[:, k]
        got = (y(dq, np.zeros(n), 0.0) - y(-dq, np.zeros(n), 0.0)) / (2 * eps)
        assert got == pytest.approx(lin.C[j, k], abs=1e-6 * scale)
        got = (y(np.zeros(n), dq, 0.0) - y(np.zeros(n), -dq, 0.0)) / (2 * eps)
        assert got == pytest.approx(lin.C[j, d + k], abs=1e-6 * scale)
    got = (y(np.zeros(n), np.zeros(n), eps) - y(np.zeros(n), np.zeros(n), -eps)) / (2 * eps)
    assert got == pytest.approx(lin.D[j, 0], abs=1e-6 * max(abs(lin.D[j, 0]), 1.0))
    assert lin.D[j, 0] != 0.0  # the guide carries part of the actuator force at once


def test_force_output_carries_the_input():
    # the actuator's force output is k δl + c δl̇ + u: D = 1 for its own input, C = k ∇l, c ∇l
    model, eq = _solved("C1")
    lin = mbseig.linearize(model, eq)
    j = list(lin.output_names).index("actuator force")
    assert lin.D[j, 0] == 1.0 and lin.D[j, 1] == 0.0
    act = next(f for f in model.forces if f.name.endswith("'actuator'"))
    np.testing.assert_allclose(lin.C[j, lin.dof:] * act.stiffness,
                               lin.C[j, :lin.dof] * act.damping, rtol=1e-12, atol=1e-15)


# --------------------------------------------------------------------------------------------
# sensitivities and energy
# --------------------------------------------------------------------------------------------
def test_sensitivities_of_the_least_stable_c2_mode_match_eigenvalue_differences():
    from mbseig.studies.design import eigen_sensitivities

    spec = _spec(_hand_text(), "hand")
    a = analyze(spec, config="C2")
    k = int(np.argmin(a.modes.delta))  # least stable: smallest decay rate
    sens = eigen_sensitivities(spec, config="C2", analysis=a, parameters=["c_a", "k_a"])
    s0 = a.modes.eigenvalues[k]

    def s_at(name, value):
        ev = analyze(spec, config="C2", params={name: value}).modes.eigenvalues
        return ev[np.argmin(np.abs(ev - s0))]

    for name, p in (("c_a", 1.0), ("k_a", 10000.0)):
        # reference: central differences of the eigenvalue, Richardson-extrapolated from steps
        # h and h/2 (error O(h⁴)); h = 1e-3 p
        h = 1e-3 * p
        d1 = (s_at(name, p + h) - s_at(name, p - h)) / (2 * h)
        d2 = (s_at(name, p + h / 2) - s_at(name, p - h / 2)) / h
        reference = (4 * d2 - d1) / 3
        assert abs(sens[name][k] - reference) <= 1e-6 * abs(reference), (name, sens[name][k],
                                                                          reference)


def test_modes_json_sensitivities(tmp_path):
    # the four-bar: g and k_crank enter; theta0 is an expression (derived) and is left out, an
    # integer count is left out, a parameter that enters nothing is left out
    text = (CASES / "four_bar.toml").read_text().replace(
        'theta0 = "deg(60)"', 'theta0 = "deg(60)"\nn_unused = 3\nunused = 2.5')
    path = tmp_path / "four_bar.toml"
    path.write_text(text)
    code, out = _cli(["modes", str(path), "--json", "--sensitivities"])
    assert code == 0
    sens = json.loads(out)["modes"][0]["sensitivity"]
    assert set(sens) == {"g", "k_crank"}
    # reference: the undamped mode ω² = k_eff/m_eff is linear in k_crank and in g, so
    # ∂s/∂k_crank · k_crank + ∂s/∂g · g = s/2 (homogeneity of degree ½ of s = iω)
    md = analyze(CASES / "four_bar.toml").modes
    s = md.eigenvalues[0]
    combo = complex(*sens["k_crank"]) * 50.0 + complex(*sens["g"]) * 9.81
    assert abs(combo - s / 2) <= 1e-7 * abs(s)


def test_modes_json_energy_angles_and_frequencies(hand_path):
    code, text = _cli(["modes", str(hand_path), "--json", "--energy"])
    assert code == 0
    d = json.loads(text)
    for m in d["modes"]:
        assert m["freq_n_hz"] == pytest.approx(m["omega_n"] / (2 * math.pi), rel=1e-15)
        assert m["freq_hz"] == pytest.approx(m["omega_d"] / (2 * math.pi), rel=1e-15)
        for kind in ("kinetic", "potential"):
            assert sum(m["energy"][kind].values()) == pytest.approx(1.0, abs=1e-12)
        # report angles, torsional elements (same names) and the angle output
        assert set(m["angles"]) == {"MCP", "PIP", "DIP", "MCP angle"}
        assert m["angles"]["MCP"] == pytest.approx(m["angles"]["MCP angle"], rel=1e-12)


def test_energy_of_a_pendulum_is_gravity_and_kinetic_matches_mass_form():
    # closed form: a point pendulum stores its potential energy in gravity alone
    from mbseig.studies.design import modal_energy

    a = analyze(CASES / "pendulum.toml")
    e = modal_energy(a.model, a.eq, a.linear, a.modes)
    assert e[0]["potential"] == pytest.approx({"gravity": 1.0}, abs=1e-12)
    # four-bar: the kinetic shares are the body blocks' quadratic forms over φᴴ M φ
    a = analyze(CASES / "four_bar.toml")
    e = modal_energy(a.model, a.eq, a.linear, a.modes)
    phi = a.linear.N @ a.modes.vectors[:, 0]
    M = a.model.mass.toarray()
    total = np.real(np.conj(phi) @ M @ phi)
    name, rows, _, block = a.model.mass_parts[0]
    v = phi[rows]
    assert e[0]["kinetic"][name] == pytest.approx(np.real(np.conj(v) @ block @ v) / total,
                                                  rel=1e-12)
    # the crank spring stores more than the whole: gravity's share is negative (it softens)
    assert e[0]["potential"]["crank spring"] > 1.0
    assert e[0]["potential"]["gravity"] < 0.0


# --------------------------------------------------------------------------------------------
# null-space basis, frequencies, the band option, Modes conveniences
# --------------------------------------------------------------------------------------------
def test_null_space_basis_is_continuous_and_leaves_eigenvalues_unchanged():
    from mbseig.numerics import null_space_basis

    lins = []
    for deg in (44, 45):
        m = mbseig.load_case(CASES / "four_bar.toml", theta0=f"deg({deg})")
        eq = mbseig.equilibrium(m)
        lins.append((m, eq, mbseig.linearize(m, eq)))
    (_, e0, l0), (m1, e1, l1) = lins
    assert np.max(np.abs(e0.q - e1.q)) > 1e-3  # the posture moved
    assert float(l0.N[:, 0] @ l1.N[:, 0]) > 0.999
    # the hand device's 3-column basis between MCP commands 44° and 45°
    b = []
    for t in (44.0, 45.0):
        m = mbseig.load_case(CASE, mcp_target=t)
        b.append(mbseig.linearize(m, mbseig.equilibrium(m)))
    G = b[0].N.T @ b[1].N
    assert np.all(np.diag(G) > 0.99) and np.max(np.abs(G - np.diag(np.diag(G)))) < 0.05
    # eigenvalues unchanged against the plain SVD basis (reference: numerics.null_space_basis)
    Z = null_space_basis(m1.phi_q(e1.q), m1.n, 1e-10)[0]
    K, C = m1.force_jacobians(e1.q)
    K = (K + m1.constraint_hessian(e1.q, e1.lam)).toarray()
    s_ref = mbseig.solve_qep(Z.T @ m1.mass.toarray() @ Z, Z.T @ C.toarray() @ Z,
                             Z.T @ K @ Z).eigenvalues
    s = mbseig.solve_qep(l1.M, l1.P, l1.Q).eigenvalues
    np.testing.assert_allclose(np.sort_complex(s), np.sort_complex(s_ref), rtol=1e-12)


def test_null_space_basis_depends_on_the_null_space_only():
    # the same null space from a reordered, rescaled Φ_q (another SVD) gives the same N
    from mbseig.linear import continuous_null_basis

    rng = np.random.default_rng(3)
    G = rng.standard_normal((3, 7))
    N1, *_ = continuous_null_basis(G, 7, 1e-12)
    N2, *_ = continuous_null_basis(np.diag([5.0, 0.1, 2.0]) @ G[[2, 0, 1]], 7, 1e-12)
    np.testing.assert_allclose(N1, N2, atol=1e-13)
    np.testing.assert_allclose(G @ N1, 0, atol=1e-13)
    np.testing.assert_allclose(N1.T @ N1, np.eye(4), atol=1e-13)


def test_band_on_a_small_model_lists_the_band(hand_path):
    code, text = _cli(["modes", str(CASE), "--band-hz", "20", "22", "--json"])
    assert code == 0
    assert json.loads(text)["modes"] == []  # no natural frequency between 20 and 22 Hz
    code, text = _cli(["modes", str(CASE), "--band-hz", "20", "50", "--json"])
    full = analyze(CASE).modes
    inside = full.freq_n_hz[(full.freq_n_hz >= 20) & (full.freq_n_hz <= 50)]
    got = [m["freq_n_hz"] for m in json.loads(text)["modes"]]
    assert inside.size >= 1 and got == pytest.approx(list(inside), rel=1e-12)


def test_modes_repr_table_and_dataframe():
    md = analyze(CASE).modes
    r = repr(md)
    assert len(r) < 200 and "3 listed" in r
    assert "f_n [Hz]" in md.table() and "f_d [Hz]" in md.table()
    pd = pytest.importorskip("pandas")
    df = md.to_dataframe()
    assert isinstance(df, pd.DataFrame) and len(df) == 3
    np.testing.assert_allclose(df["freq_n_hz"], md.omega_n / (2 * np.pi))
    np.testing.assert_allclose(df["freq_hz"], md.omega_d / (2 * np.pi))


def test_signal_units_label_the_bode_plot(tmp_path):
    """Units of u and y as DESIGN.md §8 defines them: an actuator (spring-damper) input is a
    force in N, a body-pair input a moment in N m, a body-pair angle output rad; the Bode
    magnitude axis carries [rad/N]."""
    from mbseig.studies.frf import bode_figure, frf

    m = mbseig.load_case(CASE)
    lin = mbseig.linearize(m, mbseig.equilibrium(m))
    units = dict(zip(lin.input_names, lin.input_units, strict=True))
    assert units == {"actuator force": "N", "MCP torque": "N m"}
    assert dict(zip(lin.output_names, lin.output_units, strict=True))["MCP angle"] == "rad"
    fig = bode_figure(frf(lin, "actuator force", "MCP angle", freq_hz=[1.0, 10.0]))
    assert fig.axes[0].get_ylabel().endswith("[rad/N]")
