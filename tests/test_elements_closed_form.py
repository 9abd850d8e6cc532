"""Each element type in a small case with a closed-form answer (tolerance 1e-10 relative).

  slider + spring         ω = √(k/m) for a mass on a line (any direction, 2-D and 3-D)
  compound pendulum       ω² = m g d / (I_G + m d²), pivot at a basic point or at a body point
  constant force          pendulum under gravity plus a horizontal force F: the effective
                          gravity is √((mg)² + F²)/m, so ω² = √(g² + (F/m)²)/l, tan φ = F/(mg)
  spherical pendulum      3-D: two equal modes ω = √(g/l) (repeated eigenvalue)
  torsional spring        bar pinned at one end, torsional spring k_t to ground, no gravity:
                          ω² = k_t / I_A
"""

import numpy as np
import pytest
from conftest import write_case

from mbseig.studies import analyze

HEAD = ("schema_version = 1\n[expected]\n"
        "source = \"closed form in tests/test_elements_closed_form.py\"\n")


def run(tmp_path, body, **params):
    return analyze(write_case(tmp_path, HEAD.replace("[expected]", body + "\n[expected]")),
                   params=params)


@pytest.mark.parametrize("direction", [[1.0, 0.0], [0.6, 0.8], [-1.0, 2.0]])
def test_slider_spring_2d(tmp_path, direction):
    d = np.array(direction) / np.linalg.norm(direction)
    body = f"""
dimension = 2
gravity = [0.0, -9.81]
[[points]]
name = "G"
position = [0.0, 0.0]
fixed = true
[[points]]
name = "S"
position = [{d[0]}, {d[1]}]
[[masses]]
point = "S"
mass = 2.0
[[joints]]
type = "slider"
point = "S"
origin = [0.0, 0.0]
direction = {direction}
[[forces]]
type = "spring"
points = ["G", "S"]
stiffness = 50.0
free_length = 0.5
"""
    a = run(tmp_path, body)
    assert a.linear.dof == 1
    assert a.modes.omega_n[0] == pytest.approx(np.sqrt(50.0 / 2.0), rel=1e-10)


def test_slider_3d_two_constraints(tmp_path):
    body = """
dimension = 3
[[points]]
name = "G"
position = [0.0, 0.0, 0.0]
fixed = true
[[points]]
name = "S"
position = [1.0, 1.0, 1.0]
[[masses]]
point = "S"
mass = 3.0
[[joints]]
type = "slider"
point = "S"
direction = [1.0, 1.0, 1.0]
[[forces]]
type = "spring"
points = ["G", "S"]
stiffness = 12.0
free_length = 1.0
"""
    a = run(tmp_path, body)
    assert a.model.n_constraints == 2 and a.linear.dof == 1
    assert a.modes.omega_n[0] == pytest.approx(2.0, rel=1e-10)


BAR = """
dimension = 2
gravity = [0.0, -9.81]
[parameters]
m = 2.0
L = 1.2
[[points]]
name = "A"
position = [0.0, 0.0]
fixed = {fixed_a}
[[points]]
name = "B"
position = [0.0, "-L"]
[[bodies]]
name = "bar"
points = ["A", "B"]
mass = "m"
inertia = "m*L**2/12"
markers = {{ pivot = [{pivot}, 0.0] }}
"""


def test_compound_pendulum_pivot_at_basic_point(tmp_path):
    a = run(tmp_path, BAR.format(fixed_a="true", pivot=0.0))
    m, L, g = 2.0, 1.2, 9.81
    d, I_G = L / 2, m * L**2 / 12
    assert a.modes.omega_n[0] == pytest.approx(np.sqrt(m * g * d / (I_G + m * d**2)), rel=1e-10)


def test_compound_pendulum_pivot_at_body_point(tmp_path):
    """Both basic points free; a `fixed` joint holds the body marker at 0.3 L."""
    body = BAR.format(fixed_a="false", pivot="\"0.3*L\"") + """
[[joints]]
type = "fixed"
point = "bar.pivot"
"""
    a = run(tmp_path, body)
    m, L, g = 2.0, 1.2, 9.81
    d, I_G = 0.2 * L, m * L**2 / 12
    assert a.linear.dof == 1 and a.model.n_constraints == 3
    assert a.modes.omega_n[0] == pytest.approx(np.sqrt(m * g * d / (I_G + m * d**2)), rel=1e-10)


def test_attach_point_to_body(tmp_path):
    """A point mass attached to the bar's tip marker adds m_p L² to the pendulum's inertia."""
    body = BAR.format(fixed_a="true", pivot=0.0) + """
[[points]]
name = "T"
position = [0.0, "-L"]
[[masses]]
point = "T"
mass = 0.5
[[joints]]
type = "attach"
point = "T"
body = "bar"
local = ["L", 0.0]
"""
    a = run(tmp_path, body)
    m, L, g, mp = 2.0, 1.2, 9.81, 0.5
    num = g * (m * L / 2 + mp * L)
    den = m * L**2 / 3 + mp * L**2
    assert a.modes.omega_n[0] == pytest.approx(np.sqrt(num / den), rel=1e-10)


def test_constant_force_pendulum(tmp_path):
    body = """
dimension = 2
gravity = [0.0, -9.81]
[[points]]
name = "O"
position = [0.0, 0.0]
fixed = true
[[points]]
name = "P"
position = [0.0, -1.0]
[[masses]]
point = "P"
mass = 1.5
[[joints]]
type = "distance"
points = ["O", "P"]
[[forces]]
type = "force"
point = "P"
vector = [4.0, 0.0]
"""
    a = run(tmp_path, body)
    m, g, F = 1.5, 9.81, 4.0
    P = a.model.points["P"](a.eq.q)
    assert np.arctan2(P[0], -P[1]) == pytest.approx(np.arctan2(F, m * g), abs=1e-12)
    assert a.modes.omega_n[0] == pytest.approx(np.sqrt(np.hypot(g, F / m)), rel=1e-10)


def test_spherical_pendulum_repeated_modes(tmp_path):
    body = """
dimension = 3
gravity = [0.0, 0.0, -9.81]
[[points]]
name = "O"
position = [0.0, 0.0, 0.0]
fixed = true
[[points]]
name = "P"
position = [0.0, 0.0, -2.0]
[[masses]]
point = "P"
mass = 1.0
[[joints]]
type = "distance"
points = ["O", "P"]
"""
    a = run(tmp_path, body)
    assert len(a.modes) == 2
    np.testing.assert_allclose(a.modes.omega_n, [np.sqrt(9.81 / 2)] * 2, rtol=1e-10)
    # mode shapes are in the full coordinates and tangent to the constraint (Φ_q x = 0)
    assert np.abs(a.model.phi_q(a.eq.q) @ a.modes.shapes).max() < 1e-12


@pytest.mark.parametrize("sense", ["ccw", "cw"])
def test_torsional_spring_to_ground(tmp_path, sense):
    body = BAR.format(fixed_a="true", pivot=0.0).replace("gravity = [0.0, -9.81]\n", "") + f"""
[[forces]]
type = "torsional"
bodies = ["ground", "bar"]
stiffness = 3.0
sense = "{sense}"
"""
    a = run(tmp_path, body)
    m, L = 2.0, 1.2
    assert a.modes.omega_n[0] == pytest.approx(np.sqrt(3.0 / (m * L**2 / 3)), rel=1e-10)
