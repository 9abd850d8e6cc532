"""The 3-D reader on small cases with closed-form statics and dynamics: torques (fixed and
follower) against a torsional spring on a revolute (θ = T/k), a force on a bushing (d = F/k),
inverse statics by an angle driver about a revolute axis, a follower force on a body point,
and the natural frequencies of a body on a bushing (√(k/m) and √(k_r/I)).  Closed forms to
1e-10 relative."""

import math

import numpy as np
import pytest
from conftest import write_case

import mbseig

HINGE = """
schema_version = 1
dimension = 3
[[bodies]]
name = "arm"
mass = 2.0
com = [0.5, 0.0, 0.0]
inertia = [0.01, 0.2, 0.2]
[[joints]]
name = "hinge"
type = "revolute"
bodies = ["ground", "arm"]
at = [0.0, 0.0, 0.0]
axis = [0.0, 0.0, 1.0]
[[forces]]
name = "spring"
type = "torsional"
joint = "hinge"
stiffness = 40.0
{extra}
"""


def hinge_angle(model, q):
    u = q[[model.coordinate_names.index(f"arm.u.{a}") for a in "xy"]]
    return math.atan2(u[1], u[0])


@pytest.mark.parametrize("follower", ["false", "true"])
def test_torque_against_torsional_spring(follower, tmp_path):
    extra = ('[[forces]]\ntype = "torque"\nbody = "arm"\nvector = [0.0, 0.0, 6.0]\n'
             f'follower = {follower}')
    model = mbseig.load_case(write_case(tmp_path, HINGE.format(extra=extra)))
    eq = mbseig.equilibrium(model)
    assert hinge_angle(model, eq.q) == pytest.approx(6.0 / 40.0, rel=1e-10)


def test_follower_force_on_a_body_point(tmp_path):
    """A force of 3 N normal to the arm at 0.5 m: θ = 1.5/40, whatever the posture."""
    extra = ('[[forces]]\ntype = "force"\npoint = { body = "arm", at = [0.5, 0.0, 0.0] }\n'
             'vector = [0.0, 3.0, 0.0]\nfollower = true')
    model = mbseig.load_case(write_case(tmp_path, HINGE.format(extra=extra)))
    eq = mbseig.equilibrium(model)
    assert hinge_angle(model, eq.q) == pytest.approx(1.5 / 40.0, rel=1e-10)


def test_angle_driver_sets_a_spring(tmp_path):
    """Inverse statics about a revolute axis: the driver's commanded angle holds with the
    spring's free length set and no driver in the final model; the spring balances the
    torsional spring there (k_t θ = F × lever)."""
    extra = ('[[forces]]\nname = "actuator"\ntype = "spring"\n'
             'points = [{ body = "ground", at = [0.5, 1.0, 0.0] }, '
             '{ body = "arm", at = [0.5, 0.0, 0.0] }]\n'
             'stiffness = 500.0\n'
             '[[joints]]\ntype = "angle_driver"\njoint = "hinge"\nangle = 0.3\nsets = "actuator"')
    model = mbseig.load_case(write_case(tmp_path, HINGE.format(extra=extra)))
    eq = mbseig.equilibrium(model)
    assert hinge_angle(eq.model, eq.q) == pytest.approx(0.3, rel=1e-10)
    (rec,) = eq.model.drivers
    assert rec["sets"][0]["element"].endswith("'actuator'")


BUSHED = """
schema_version = 1
dimension = 3
[[bodies]]
name = "b"
mass = 3.0
com = [0.1, 0.2, 0.3]
inertia = [0.02, 0.03, 0.04]
[[forces]]
type = "bushing"
bodies = ["ground", "b"]
at = [0.1, 0.2, 0.3]
stiffness = [100.0, 200.0, 300.0, 4.0, 5.0, 6.0]
[[forces]]
type = "force"
point = { body = "b", at = [0.1, 0.2, 0.3] }
vector = [1.0, -2.0, 0.0]
"""


def test_bushing_statics_and_frequencies(tmp_path):
    model = mbseig.load_case(write_case(tmp_path, BUSHED))
    eq = mbseig.equilibrium(model)
    r = eq.q[[model.coordinate_names.index(f"b.{a}") for a in "xyz"]]
    np.testing.assert_allclose(r - [0.1, 0.2, 0.3], [1.0 / 100, -2.0 / 200, 0.0], atol=1e-15)
    md = mbseig.modes(mbseig.linearize(model, eq))
    # at the displaced equilibrium the bushing's strains are not zero, but a force at the
    # bushing point leaves the rotations uncoupled: √(k/m), √(k_r/I)
    ref = sorted([math.sqrt(k / 3.0) for k in (100.0, 200.0, 300.0)]
                 + [math.sqrt(kr / i) for kr, i in ((4.0, 0.02), (5.0, 0.03), (6.0, 0.04))])
    np.testing.assert_allclose(np.sort(md.omega_n), ref, rtol=1e-10)
