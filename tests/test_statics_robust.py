"""Robust statics (issue 10): equilibria found from the case's positions where the old Newton
failed, the statically unstable ones flagged with a stable rest position offered, and failures
that say what is true (docs/design.md, "Equilibrium").

References (each test names its own): symmetry (a straight chain or arm hanging from a pin hangs
straight down), closed forms of the one-link column (P L sin θ = k θ) and of the pendulum, an
independent one-coordinate energy reduction of the four-bar (loop closure by the law of cosines,
stationary points of the potential by Brent's method on its central-difference derivative), and
the complementary-energy (Menabrea) closed form of two collinear rods with compliances.
"""

import math
import warnings

import numpy as np
import pytest
from conftest import CASES, write_case
from scipy.optimize import brentq

import mbseig
from mbseig.statics import (ConstraintsUnsatisfiable, NoStaticEquilibrium, NotConverged,
                            StaticInstabilityWarning, UndeterminedSelfStress)

PENDULUM = """
schema_version = 1
title = "pendulum"
dimension = 2
gravity = [0.0, "-g"]
[parameters]
g = 9.81
th = 90.0
[[points]]
name = "O"
position = [0.0, 0.0]
fixed = true
[[points]]
name = "P"
position = ["sin(deg(th))", "-cos(deg(th))"]
[[masses]]
point = "P"
mass = 1.0
[[joints]]
type = "distance"
name = "rod"
points = ["O", "P"]
length = 1.0
"""

COLUMN = """
schema_version = 1
title = "one-link column: rigid massless bar, base spring k, dead load P at the top"
dimension = 2
[parameters]
k = 1.0
L = 1.0
P = 1.5
th = 0.0
[[points]]
name = "O"
position = [0.0, 0.0]
fixed = true
[[points]]
name = "T"
position = ["L*sin(deg(th))", "L*cos(deg(th))"]
[[masses]]
point = "T"
mass = 1.0
[[bodies]]
name = "bar"
points = ["O", "T"]
length = "L"
mass = 0.0
inertia = 0.0
[[forces]]
type = "torsional"
name = "base spring"
bodies = ["ground", "bar"]
ground_direction = [0.0, 1.0]
stiffness = "k"
angle0 = 0.0
[[forces]]
type = "force"
name = "load"
point = "T"
vector = [0.0, "-P"]
"""


def _angle_from_vertical_down(q):
    return math.atan2(q[0], -q[1])


def test_pendulum_started_horizontal_hangs_down(tmp_path):
    """λ = 0 and K = 0 at the start (no restoring force): the free-motion step takes it down.
    Reference: the hanging position (0, −1) (closed form), to 1e-12 m."""
    eq = mbseig.equilibrium(mbseig.load_case(write_case(tmp_path, PENDULUM)))
    np.testing.assert_allclose(eq.q, [0.0, -1.0], atol=1e-12)
    assert eq.static["verdict"] == "stable" and eq.correction <= eq.tolerances["xtol"]
    assert "criterion" in eq.tolerances and eq.tolerances["force_scale"] > 0


def test_inverted_pendulum_flagged_and_stable_rest_offered(tmp_path):
    """Started above the horizontal, Newton converges to the top (an equilibrium, so it is
    returned), which is flagged statically unstable; the bottom is offered (closed forms)."""
    model = mbseig.load_case(write_case(tmp_path, PENDULUM), th=120.0)
    with pytest.warns(StaticInstabilityWarning, match="statically unstable"):
        eq = mbseig.equilibrium(model)
    np.testing.assert_allclose(eq.q, [0.0, 1.0], atol=1e-12)
    assert eq.static["verdict"] == "unstable" and eq.static["index"] == 1
    alt = eq.stable_alternative
    assert alt is not None and alt.static["verdict"] == "stable"
    np.testing.assert_allclose(alt.q, [0.0, -1.0], atol=1e-12)


def test_column_past_buckling_offers_the_buckled_position(tmp_path):
    """P L = 1.5 k: the straight column is an unstable equilibrium; the offered rest position is
    the buckled one, θ/sin θ = P L / k (closed form of the one-link column), to 1e-9 rad."""
    model = mbseig.load_case(write_case(tmp_path, COLUMN))
    with pytest.warns(StaticInstabilityWarning):
        eq = mbseig.equilibrium(model)
    assert abs(eq.q[0]) < 1e-12 and eq.static["verdict"] == "unstable"
    theta_ref = brentq(lambda t: t / math.sin(t) - 1.5, 0.1, 3.0, xtol=1e-15)
    alt = eq.stable_alternative
    theta = math.atan2(alt.q[0], alt.q[1])
    assert abs(abs(theta) - theta_ref) < 1e-9


WELDED = """
schema_version = 1
title = "rigid pendulum arm with a steel beam welded to it, started horizontal"
dimension = 2
gravity = [0.0, "-g"]
[parameters]
g = 9.81
[[points]]
name = "O"
position = [0.0, 0.0]
fixed = true
[[points]]
name = "A"
position = [0.5, 0.0]
[[points]]
name = "B"
position = [1.5, 0.0]
[[bodies]]
name = "arm"
points = ["O", "A"]
mass = 2.0
inertia = 0.04
[[beams]]
name = "beam"
points = ["A", "B"]
E = 2.1e11
rho = 7850.0
section = { shape = "rectangle", b = 0.02, h = 0.01 }
elements = 4
ends = ["arm", "free"]
"""


def test_welded_beam_pendulum_swings_down(tmp_path):
    """A stiff steel beam (EA ≈ 4e7 N) welded to a soft pendulum (m g L ≈ 20 N m): the swing by
    90° converges (the old test relative to ‖K‖·L did not).  Reference: by symmetry the straight
    arm and beam hang straight down, every x = 0 (1e-9 m) and every node angle −π/2."""
    eq = mbseig.equilibrium(mbseig.load_case(write_case(tmp_path, WELDED)))
    names = eq.model.coordinate_names
    xs = [eq.q[i] for i, nm in enumerate(names) if nm.endswith(".x")]
    thetas = [eq.q[i] for i, nm in enumerate(names) if nm.endswith(".theta")]
    assert max(abs(x) for x in xs) < 1e-9
    np.testing.assert_allclose(np.mod(thetas, 2 * np.pi), 1.5 * np.pi, atol=1e-9)
    assert eq.static["verdict"] == "stable" and eq.correction <= eq.tolerances["xtol"]


CHAIN = """
schema_version = 1
title = "hanging chain of point masses on rods, started straight at 30 degrees"
dimension = 2
gravity = [0.0, "-g"]
[parameters]
g = 9.81
n = 200
a = 0.01
ang = 30.0
[[points]]
name = "O"
position = [0.0, 0.0]
fixed = true
[[points]]
name = "m{i}"
repeat = { i = [1, "n"] }
position = ["i*a*sin(deg(ang))", "-i*a*cos(deg(ang))"]
[[masses]]
repeat = { i = [1, "n"] }
point = "m{i}"
mass = 0.01
[[joints]]
type = "distance"
points = ["O", "m1"]
length = "a"
[[joints]]
type = "distance"
repeat = { i = [1, "n - 1"] }
points = ["m{i}", "m{i + 1}"]
length = "a"
"""


def test_hanging_chain_of_200_links(tmp_path):
    """200 rods: the convergence test with the final least-squares λ (the old one used the
    iterated λ and failed at 1.7e-12 against 1e-12).  Reference: hanging straight down,
    x_i = 0, y_i = −i a (symmetry), to 1e-10 m."""
    eq = mbseig.equilibrium(mbseig.load_case(write_case(tmp_path, CHAIN)))
    q = eq.q.reshape(-1, 2)
    np.testing.assert_allclose(q[:, 0], 0.0, atol=1e-10)
    np.testing.assert_allclose(q[:, 1], -0.01 * np.arange(1, 201), atol=1e-10)
    assert eq.static["verdict"] == "stable" and eq.n_redundant == 0


# --- the bundled four-bar with a soft crank spring, against a one-coordinate reduction ------
def _four_bar_energy(theta, k):
    """Potential energy of cases/four_bar.toml as a function of the crank angle (elbow up)."""
    B = 0.3 * np.array([math.cos(theta), math.sin(theta)])
    D = np.array([1.0, 0.0])
    d = np.linalg.norm(D - B)
    a = (1.0**2 - 0.8**2 + d * d) / (2 * d)
    h = math.sqrt(1.0 - a * a)
    e = (D - B) / d
    C = B + a * e + h * np.array([-e[1], e[0]])  # the upper intersection
    y_cm = 1.0 * B[1] / 2 + 2.0 * (B[1] + C[1]) / 2 + 1.5 * C[1] / 2
    return 0.5 * k * (theta - math.radians(60)) ** 2 + 9.81 * y_cm


def _dV(theta, k, h=1e-6):
    return (_four_bar_energy(theta + h, k) - _four_bar_energy(theta - h, k)) / (2 * h)


def test_four_bar_soft_crank_spring():
    """k_crank = 5 (the old Newton said "constraints are inconsistent"): the equilibrium is the
    stationary point of the one-coordinate potential near 4.31° (independent reduction, Brent on
    the central-difference derivative), to 1e-7 rad, and statically stable."""
    eq = mbseig.equilibrium(mbseig.load_case(CASES / "four_bar.toml", k_crank=5.0))
    B = eq.q[:2]
    theta = math.atan2(B[1], B[0])
    ref = brentq(lambda t: _dV(t, 5.0), math.radians(-10), math.radians(20), xtol=1e-14)
    assert abs(theta - ref) < 1e-7 and abs(math.degrees(ref) - 4.31) < 0.01
    assert eq.static["verdict"] == "stable"


def test_four_bar_potential_maximum_flagged():
    """k_crank = 3: Newton from the case's positions lands on the potential maximum (≈ 103°),
    which is flagged; the offered position is a minimum of the one-coordinate potential
    (dV/dθ = 0 to 1e-7 of m g L, d²V/dθ² > 0, independent reduction)."""
    model = mbseig.load_case(CASES / "four_bar.toml", k_crank=3.0)
    with pytest.warns(StaticInstabilityWarning):
        eq = mbseig.equilibrium(model)
    theta = math.atan2(eq.q[1], eq.q[0])
    assert abs(math.degrees(theta) - 103) < 1 and eq.static["verdict"] == "unstable"
    alt = eq.stable_alternative
    t_alt = math.atan2(alt.q[1], alt.q[0])
    assert abs(_dV(t_alt, 3.0)) < 1e-7 * 9.81 * 4.5
    assert _dV(t_alt + 1e-3, 3.0) > _dV(t_alt - 1e-3, 3.0)


# --- failures that say what is true -----------------------------------------------------------
def test_constraints_cannot_be_satisfied_names_the_constraint(tmp_path):
    text = PENDULUM + ('\n[[points]]\nname = "F"\nposition = [5.0, 0.0]\nfixed = true\n'
                       '\n[[joints]]\ntype = "distance"\nname = "too short"\npoints = ["F", "P"]\n'
                       'length = 1.0\n')
    with pytest.raises(ConstraintsUnsatisfiable,
                       match=r"joints\[[01]\] '(too short|rod)': the constraints cannot be "
                             r"satisfied: the position solve of Φ = 0 alone stops at a "
                             r"least-squares minimum") as info:
        mbseig.equilibrium(mbseig.load_case(write_case(tmp_path, text)))
    assert "too short" in str(info.value)  # named as the one off, or among the others off


def test_free_motion_is_named(tmp_path):
    text = PENDULUM[:PENDULUM.index("[[joints]]")]  # the mass without its rod: free fall
    with pytest.raises(NoStaticEquilibrium,
                       match=r"equilibrium: no static equilibrium: free motion along P\.y"):
        mbseig.equilibrium(mbseig.load_case(write_case(tmp_path, text)))


def test_not_converged_names_the_coordinates_and_gives_a_hint():
    """Two Newton iterations without continuation are not enough for the soft four-bar: the
    message is the third kind, with the coordinates that moved most and a hint."""
    model = mbseig.load_case(CASES / "four_bar.toml", k_crank=5.0)
    with pytest.raises(NotConverged) as info:
        mbseig.equilibrium(model, max_iter=2, continuation=False)
    msg = str(info.value)
    assert "did not converge from the given positions" in msg
    assert "the coordinates that moved most: " in msg and "hint: start nearer" in msg
    assert len(msg.splitlines()) == 1


COLLINEAR = """
schema_version = 1
title = "a point held by two collinear rods along gravity (a redundant pair with self-stress)"
dimension = 2
gravity = [0.0, "-g"]
[parameters]
g = 9.81
[[points]]
name = "A"
position = [0.0, 1.0]
fixed = true
[[points]]
name = "B"
position = [0.0, -1.0]
fixed = true
[[points]]
name = "P"
position = [0.0, 0.0]
[[masses]]
point = "P"
mass = 1.0
[[joints]]
type = "distance"
name = "top"
points = ["A", "P"]
[[joints]]
type = "distance"
name = "bottom"
points = ["P", "B"]
"""


def test_self_stress_refused_then_determined_by_compliance(tmp_path):
    """Every split T_top − T_bottom = m g balances the weight, and the lateral stiffness
    (T_top + T_bottom)/a depends on it: refused.  With axial compliances c_t, c_b the least
    complementary energy gives T_top = m g c_b/(c_t + c_b), T_bottom = −m g c_t/(c_t + c_b)
    (Menabrea), so ω² = (c_b − c_t)/(c_t + c_b) · g/a: with c_b = 3 c_t, ω² = g/(2a) (1e-10)."""
    model = mbseig.load_case(write_case(tmp_path, COLLINEAR))
    with pytest.raises(UndeterminedSelfStress, match=r"self-stress that statics cannot determine"):
        mbseig.equilibrium(model)
    names = [c.name for c in model.constraints]
    top, bottom = (n for n in names if "top" in n), (n for n in names if "bottom" in n)
    eq = mbseig.equilibrium(model, compliance={next(top): 1e-6, next(bottom): 3e-6})
    md = mbseig.modes(mbseig.linearize(model, eq))
    omega2 = float(np.max(md.omega_n)) ** 2
    assert omega2 == pytest.approx(9.81 / 2, rel=1e-10)
    rows = {r["element"]: r["axial_force"]
            for r in mbseig.statics.reactions.reaction_forces(model, eq)}
    assert rows[[n for n in names if "top" in n][0]] == pytest.approx(0.75 * 9.81, rel=1e-12)


def test_warning_free_for_stable_cases():
    """The bundled pendulum and four-bar are stable: no instability warning."""
    with warnings.catch_warnings():
        warnings.simplefilter("error", StaticInstabilityWarning)
        for name in ("pendulum.toml", "four_bar.toml", "double_pendulum.toml"):
            eq = mbseig.equilibrium(mbseig.load_case(CASES / name))
            assert eq.static["verdict"] == "stable"
