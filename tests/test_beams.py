"""Planar beams (mbseig.model.beams, mbseig.flexible, mbseig.refine).

References: Euler–Bernoulli cantilever β_n L = 1.8751041, 4.6940911, 7.8547574 (roots of
cos x cosh x = −1) and simply supported β_n L = nπ (Blevins, Formulas for Natural Frequency and
Mode Shape, table 8-1); the Timoshenko frequency equation of a simply supported beam (closed
form, solved below); the Euler buckling load π²EI/(4L²) of a cantilever.  Jacobians against
central differences (relative 1e-6) and complex steps are not possible through atan2 wraps.
"""

import math
import warnings

import numpy as np
import pytest
import scipy.linalg as sla
import scipy.optimize as so
from conftest import CASES, write_case

import mbseig
from mbseig.casefile.flexible import BeamTheoryWarning
from mbseig.errors import CaseError
from mbseig.model.affine import Affine
from mbseig.model.beams import THEORIES, BeamElement, BeamSection, RotationLock
from mbseig.studies import analyze

RTOL_JAC = 1e-6  # central differences, step 1e-7 on O(1) coordinates
ACCURACY = 1e-3  # the accuracy the cases request and the issue asks for (0.1 %)


def _num_jac(fun, q, h=1e-7):
    J = np.zeros((fun(q).size, q.size))
    for j in range(q.size):
        e = np.zeros(q.size)
        e[j] = h
        J[:, j] = (fun(q + e) - fun(q - e)) / (2 * h)
    return J


@pytest.mark.parametrize("theory", THEORIES)
def test_element_tangent_matches_differences(theory):
    """K = −∂g/∂q of a deformed, rotated, stretched element (the geometric stiffness included),
    g = −∂U/∂q, and K symmetric (a conservative element)."""
    rng = np.random.default_rng(3)
    s = BeamSection(E=2e11, G=8e10, A=1e-3, I=2e-7, rho=7800, kappa=5 / 6, theory=theory)
    el = BeamElement("e", Affine.select(np.arange(6)), s, 0.5)
    for _ in range(3):
        q = np.array([0.0, 0.0, 0.6, 0.42, 0.3, 0.7]) + 0.02 * rng.standard_normal(6)
        K, C = el.jacobians(q, None)
        Kn = -_num_jac(lambda x: el.force(x, None), q)
        assert np.abs(K - Kn).max() <= RTOL_JAC * np.abs(K).max()
        gU = -_num_jac(lambda x: np.array([el.strain_energy(x)]), q)[0]
        assert np.abs(gU - el.force(q, None)).max() <= RTOL_JAC * np.abs(gU).max()
        np.testing.assert_allclose(K, K.T, atol=1e-12 * np.abs(K).max())
        assert not C.any()


def test_rotation_lock_derivatives():
    """Φ_q, Σλ∇²Φ and γ of the weld between a beam node angle and a body direction."""
    c = RotationLock("lock", Affine.select(np.arange(3)), 0.3)
    w = np.array([0.8, 0.5, 1.2])
    np.testing.assert_allclose(c.jac(w), _num_jac(c.phi, w), rtol=1e-7, atol=1e-9)
    H = c.hess(w, np.array([2.0]))
    np.testing.assert_allclose(H, 2.0 * _num_jac(lambda x: c.jac(x)[0], w), atol=1e-7)
    wd = np.array([0.1, -0.2, 0.3])
    assert c.gamma(w, wd)[0] == pytest.approx(-(wd @ c.hess(w, np.array([1.0])) @ wd))


def test_rigid_motion_is_stress_free():
    """A rigid rotation and translation of an element produces no force (co-rotational)."""
    s = BeamSection(E=2e11, G=8e10, A=1e-3, I=2e-7, rho=7800, kappa=5 / 6, theory="timoshenko")
    el = BeamElement("e", Affine.select(np.arange(6)), s, 0.5)
    a = 2.5
    q = np.array([0.3, -0.2, a, 0.3 + 0.5 * math.cos(a), -0.2 + 0.5 * math.sin(a), a])
    assert np.abs(el.force(q, None)).max() < 1e-6  # forces scale with EA = 2e8 N
    # and the kinetic energy of a rigid rotation about node 1 is that of a bar: ½ (ρAl³/3 + ρIl) Ω²
    qd = np.array([0.0, 0.0, 1.0, -0.5 * math.sin(a), 0.5 * math.cos(a), 1.0])
    T = 0.5 * qd @ el.mass(q) @ qd
    T_ref = 0.5 * (7800 * 1e-3 * 0.5**3 / 3 + 7800 * 2e-7 * 0.5)
    assert T == pytest.approx(T_ref, rel=1e-12)


def _lowest(a, k=3):
    return np.sort(a.modes.omega_n)[:k]


def test_cantilever_euler_bernoulli_at_chosen_mesh():
    """The first three cantilever frequencies within 0.1 % at the mesh the refinement chose, and
    the refinement stopped before doubling once more."""
    a = analyze(CASES / "cantilever_beam.toml")
    p = a.model.parameters
    scale = math.sqrt(p["E"] * p["I"] / (p["rho"] * p["A"] * p["L"] ** 4))
    ref = np.array([1.8751041, 4.6940911, 7.8547574]) ** 2 * scale
    np.testing.assert_allclose(_lowest(a), ref, rtol=ACCURACY)
    r = a.refinement
    assert r.converged and r.estimated_error <= ACCURACY
    n = r.beams["beam"]["elements"]
    # the chosen mesh is the smallest of the sequence 2, 4, 8, ... that meets the accuracy
    coarser = analyze(CASES / "cantilever_beam.toml", refine={"modes": 3, "accuracy": 1.0})
    assert coarser.refinement.beams["beam"]["elements"] < n


def test_simply_supported_euler_bernoulli():
    a = analyze(CASES / "simply_supported_beam.toml")
    p = a.model.parameters
    ref = (np.arange(1, 4) * np.pi / p["L"]) ** 2 * math.sqrt(p["E"] * p["I"] / (p["rho"] * p["A"]))
    np.testing.assert_allclose(_lowest(a), ref, rtol=ACCURACY)


def timoshenko_ss(n, *, E, G, kap, A, I_area, rho, L):
    """Lower root of the Timoshenko frequency equation, pinned-pinned, k = nπ/L (I_area: the
    second moment of area I)."""
    k = n * np.pi / L
    kGA = kap * G * A
    # (ρA ω² − kGA k²)(ρI ω² − EI k² − kGA) − (kGA k)² = 0, a quadratic in ω²
    c2 = rho * A * rho * I_area
    c1 = -(rho * A * (E * I_area * k**2 + kGA) + rho * I_area * kGA * k**2)
    c0 = kGA * k**2 * (E * I_area * k**2 + kGA) - (kGA * k) ** 2
    return math.sqrt((-c1 - math.sqrt(c1 * c1 - 4 * c2 * c0)) / (2 * c2))


def test_timoshenko_simply_supported_closed_form():
    a = analyze(CASES / "timoshenko_beam.toml")
    p = a.model.parameters
    ref = [timoshenko_ss(n, E=p["E"], G=p["G"], kap=p["kap"], A=p["A"], I_area=p["I"],
                         rho=p["rho"], L=p["L"]) for n in (1, 2, 3)]
    np.testing.assert_allclose(_lowest(a), ref, rtol=ACCURACY)
    # shear and rotary inertia matter here: Euler–Bernoulli is 2 % to 15 % too stiff
    eb = (np.arange(1, 4) * np.pi / p["L"]) ** 2 * math.sqrt(p["E"] * p["I"] / (p["rho"] * p["A"]))
    assert np.all(eb / np.array(ref) > 1.02)
    rec = a.model.flexible["bodies"]["beam"]
    assert rec["theory"] == "timoshenko" and rec["slenderness"] == pytest.approx(8.0)


def _fixed_mesh_case(tmp_path, n):
    text = (CASES / "cantilever_beam.toml").read_text()
    text = text.replace('elements = "auto"', f"elements = {n}")
    text = text.split("[refinement]")[0]
    return write_case(tmp_path, text)


def test_euler_buckling_load(tmp_path):
    """ω₁² crosses zero at the Euler load π²EI/(4L²) (within 0.5 %; found by Brent's method),
    tension raises ω₁ and compression lowers it."""
    path = _fixed_mesh_case(tmp_path, 8)

    def w1sq(P):
        m = mbseig.load_case(path, P=P)
        lin = mbseig.linearize(m, mbseig.equilibrium(m))
        return sla.eigh(lin.Q, lin.M, eigvals_only=True)[0]

    p = mbseig.load_case(path).parameters
    P_euler = math.pi**2 * p["E"] * p["I"] / (4 * p["L"] ** 2)
    P_cr = so.brentq(w1sq, 0.5 * P_euler, 1.5 * P_euler, xtol=1e-6 * P_euler)
    assert P_cr == pytest.approx(P_euler, rel=5e-3)
    w0 = w1sq(0.0)
    assert w1sq(-0.5 * P_euler) > 1.3 * w0  # tension stiffens
    assert w1sq(0.5 * P_euler) < 0.6 * w0  # compression softens
    # beyond the load the first mode is a divergence and the verdict says so
    m = mbseig.load_case(path, P=1.05 * P_euler)
    eq = mbseig.equilibrium(m)
    lin = mbseig.linearize(m, eq)
    md = mbseig.modes(lin.M, lin.P, lin.Q)
    assert md.verdict == "unstable" and "divergence" in md.kind


def test_refinement_leaves_irrelevant_beams_coarse(tmp_path):
    """Two beams in one case; a stiff short one hardly moves the lowest mode of the long one, so
    it stays at the starting mesh while the long one is refined."""
    text = """
schema_version = 1
dimension = 2
[[points]]
name = "A"
position = [0.0, 0.0]
fixed = true
[[points]]
name = "B"
position = [1.0, 0.0]
[[points]]
name = "C"
position = [0.0, 1.0]
fixed = true
[[points]]
name = "D"
position = [0.1, 1.0]
[[beams]]
name = "long"
points = ["A", "B"]
E = 2.1e11
rho = 7850
A = 2e-4
I = 1.6667e-9
ends = ["clamped", "free"]
[[beams]]
name = "stub"
points = ["C", "D"]
E = 2.1e11
rho = 7850
A = 2e-4
I = 1.6667e-9
ends = ["clamped", "free"]
[refinement]
modes = 2
accuracy = 1e-3
[expected]
source = "none"
"""
    a = analyze(write_case(tmp_path, text))
    beams = a.refinement.beams
    assert beams["stub"]["elements"] == 2
    assert beams["long"]["elements"] > 2


def test_slenderness_warnings(tmp_path):
    base = (CASES / "cantilever_beam.toml").read_text()
    stubby = base.replace('h = 0.01          # m, depth', 'h = 0.15          # m, depth')
    path = write_case(tmp_path, stubby)
    with pytest.warns(BeamTheoryWarning, match="Euler–Bernoulli theory at slenderness"):
        m = mbseig.load_case(path)
    assert m.flexible["bodies"]["beam"]["warnings"]
    very = base.replace('h = 0.01          # m, depth', 'h = 0.3           # m, depth')
    very = very.replace('theory = "euler-bernoulli"', 'theory = "timoshenko"\nnu = 0.3')
    with pytest.warns(BeamTheoryWarning, match="beam theory is inaccurate"):
        mbseig.load_case(write_case(tmp_path, very, "v.toml"))
    with warnings.catch_warnings():
        warnings.simplefilter("error", BeamTheoryWarning)
        m = mbseig.load_case(CASES / "cantilever_beam.toml")
    assert m.flexible["bodies"]["beam"]["slenderness"] == pytest.approx(100.0)


@pytest.mark.parametrize("edit, message", [
    (('theory = "euler-bernoulli"', 'theory = "bernoulli"'), "theory must be one of"),
    (('elements = "auto"', "elements = 0"), "elements must be an integer"),
    (('ends = ["clamped", "free"]', 'ends = ["clamped", "nobody"]'), "neither"),
    (('theory = "euler-bernoulli"', 'theory = "timoshenko"'), "needs the shear modulus"),
])
def test_bad_beam_input(tmp_path, edit, message):
    text = (CASES / "cantilever_beam.toml").read_text().replace(*edit)
    with pytest.raises(CaseError, match=message) as info:
        mbseig.load_case(write_case(tmp_path, text))
    assert "beams[0] 'beam'" in str(info.value) and "case.toml" in str(info.value)


def test_cli_refine_options_extend_json(capsys):
    import json

    from mbseig.cli import main

    path = str(CASES / "cantilever_beam.toml")
    assert main(["modes", path, "--json", "--refine-modes", "2", "--accuracy", "1e-2"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["refinement"]["modes"] == 2 and out["refinement"]["accuracy"] == 1e-2
    assert out["refinement"]["estimated_error"] <= 1e-2
    beam = out["flexible_bodies"]["beam"]
    assert beam["theory"] == "euler-bernoulli" and beam["slenderness"] == pytest.approx(100.0)
    assert beam["elements"] == out["refinement"]["beams"]["beam"]["elements"]
    assert main(["modes", path, "--refine-modes", "0"]) == 2
    assert "--refine-modes must be a positive integer" in capsys.readouterr().err
