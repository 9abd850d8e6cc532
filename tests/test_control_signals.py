"""[[inputs]] / [[outputs]] in the planar and spatial readers: what is read, what is refused.

References: the spatial DC gains are checked against nonlinear statics with the torsional
element's zero angle shifted (an input u on a torsional element is exactly a shift of angle0 by
−u/k), and against the moment input's own sign convention (a moment about the joint axis on
the crank does the work of −u on the element); the error cases assert the one-line message.
"""

import dataclasses
import io
import tomllib
from contextlib import redirect_stderr, redirect_stdout

import numpy as np
import pytest
from conftest import CASES

import mbseig
from mbseig import casefile
from mbseig.casefile import CaseSpec
from mbseig.cli import main
from mbseig.errors import CaseError
from mbseig.model.signals import output_value
from mbseig.studies.frf import dc_gain


@pytest.fixture(autouse=True, scope="module")
def _signal_tables():
    # until mbseig/casefile/__init__.py's _TOP_KEYS names [[inputs]] and [[outputs]] (a no-op
    # once it does)
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(casefile, "_TOP_KEYS", casefile._TOP_KEYS | {"inputs", "outputs"})
        yield


def _build(text, name="case", **params):
    return CaseSpec(tomllib.loads(text), name, f"{name}.toml").build(None, **params)


ARM = """
schema_version = 1
dimension = 3
gravity = [0.0, 0.0, -9.81]
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
axis = [0.0, 1.0, 0.0]
[[forces]]
name = "spring"
type = "torsional"
joint = "hinge"
stiffness = 50.0
[[forces]]
name = "tip load"
type = "force"
point = { body = "arm", at = [1.0, 0.0, 0.0] }
vector = [0.0, 0.0, -2.0]

[[inputs]]
name = "arm moment"
body = "arm"
axis = [0.0, 1.0, 0.0]
[[inputs]]
name = "spring moment"
element = "spring"
[[inputs]]
name = "tip load"
element = "tip load"
[[inputs]]
name = "tip push"
point = { body = "arm", at = [1.0, 0.0, 0.0] }
direction = [0.0, 0.0, -1.0]

[[outputs]]
name = "hinge angle"
quantity = "angle"
element = "spring"
[[outputs]]
name = "spring moment"
quantity = "moment"
element = "spring"
[[outputs]]
name = "tip z"
quantity = "position"
point = { body = "arm", at = [1.0, 0.0, 0.0] }
direction = [0.0, 0.0, 1.0]
"""


def test_spatial_inputs_outputs_and_dc_gain():
    model = _build(ARM, "arm")
    eq = mbseig.equilibrium(model)
    lin = mbseig.linearize(model, eq)
    assert lin.dof == 1
    assert lin.input_names == ("arm moment", "spring moment", "tip load", "tip push")
    # a moment +u about the hinge axis on the arm does the work of −u added to the spring's
    # moment (which acts against the angle); a load's magnitude is a point force along its
    # unit vector
    np.testing.assert_allclose(lin.B[:, 0], -lin.B[:, 1], rtol=1e-12)
    np.testing.assert_allclose(lin.B[:, 2], lin.B[:, 3], rtol=1e-12)
    assert lin.D[1, 1] == 1.0  # the moment output carries its own element's input
    # reference: nonlinear statics with angle0 shifted by ∓ε/k (exactly an extra moment ±ε)
    spring = next(f for f in model.forces if f.name.endswith("'spring'"))
    out = model.outputs[0]
    eps = 1e-4

    def angle(u):
        forces = tuple(dataclasses.replace(f, angle0=f.angle0 - u / f.stiffness)
                       if f is spring else f for f in model.forces)
        m = dataclasses.replace(model, forces=forces, q_init=eq.q)
        return output_value(m, out, mbseig.equilibrium(m).q, np.zeros(m.n))

    reference = (angle(eps) - angle(-eps)) / (2 * eps)
    assert dc_gain(lin, "spring moment", "hinge angle") == pytest.approx(reference, rel=1e-6)
    # reference: nonlinear statics with the constant load changed by ±ε along its vector
    tip = model.inputs[3]
    b = tip.generalized_force(model, eq.q)

    def tip_z(u):
        m = dataclasses.replace(model, g_const=model.g_const + u * b, q_init=eq.q)
        return output_value(m, model.outputs[2], mbseig.equilibrium(m).q, np.zeros(m.n))

    reference = (tip_z(eps) - tip_z(-eps)) / (2 * eps)
    assert dc_gain(lin, "tip load", "tip z") == pytest.approx(reference, rel=1e-6)


PLANAR = """
schema_version = 1
dimension = 2
gravity = [0.0, -9.81]
[[points]]
name = "O"
position = [0.0, 0.0]
fixed = true
[[points]]
name = "P"
position = [1.0, 0.0]
[[masses]]
point = "P"
mass = 1.0
[[joints]]
type = "distance"
name = "rod"
points = ["O", "P"]
[[forces]]
type = "spring"
name = "s"
points = ["O", "P"]
stiffness = 10.0
[[forces]]
type = "force"
name = "load"
point = "P"
vector = [0.0, -2.0]
"""


def test_planar_reaction_force_input_and_names():
    model = _build(PLANAR + """
[[inputs]]
name = "load"
element = "load"
[[outputs]]
name = "rod force"
quantity = "force"
element = "rod"
[[outputs]]
name = "P y"
quantity = "position"
point = "P"
direction = [0.0, 1.0]
""")
    eq = mbseig.equilibrium(model)
    lin = mbseig.linearize(model, eq)
    # reference (statics by hand): the pendulum hangs straight down and its rod carries the
    # weight and the load in tension, m g + 2 N = 11.81 N (2λL, tension positive)
    np.testing.assert_allclose(eq.q, [0.0, -1.0], atol=1e-12)
    rod = output_value(model, model.outputs[0], eq.q, np.zeros(model.n), eq.lam)
    assert rod == pytest.approx(9.81 + 2.0, rel=1e-12)
    # the load along its own vector (−y, along the hanging rod): the rod's tension follows at
    # once by the full load (D = 1), the swing is not excited (C = 0, B = 0)
    assert lin.D[0, 0] == pytest.approx(1.0, rel=1e-12)
    assert np.max(np.abs(lin.C)) <= 1e-12 and np.max(np.abs(lin.B)) <= 1e-12


@pytest.mark.parametrize("table, message", [
    ('[[inputs]]\nname = "u"\nelement = "nope"\n', "unknown element 'nope'"),
    ('[[inputs]]\nname = "u"\nelement = "s"\ncolour = 1\n', "unknown field 'colour'"),
    ('[[inputs]]\nname = "u"\npoint = "P"\ndirection = [1.0, 1.0]\n', "unit vector"),
    ('[[inputs]]\nname = "u"\npoint = "P"\nelement = "s"\ndirection = [1.0, 0.0]\n',
     "exactly one of"),
    ('[[inputs]]\nname = "u"\nelement = "rod"\n', "takes no input"),
    ('[[outputs]]\nname = "y"\nquantity = "angle"\nelement = "s"\n', "quantity 'angle'"),
    ('[[outputs]]\nname = "y"\nquantity = "force"\nelement = "load"\n', "has no output"),
    (('[[outputs]]\nname = "y"\nquantity = "position"\npoint = "P"\ndirection = [1.0, 0.0]\n'
      '[[outputs]]\nname = "y"\nquantity = "velocity"\npoint = "P"\ndirection = [1.0, 0.0]\n'),
     "duplicate output name 'y'"),
    ('[[outputs]]\nname = "y"\nquantity = "force"\nelement = "s"\nsense = "cw"\n',
     "unknown field 'sense'"),
])
def test_bad_signal_tables_are_refused(table, message):
    with pytest.raises(CaseError, match=message):
        _build(PLANAR + table)


def test_vector_reaction_needs_a_direction():
    text = PLANAR.replace('type = "distance"\nname = "rod"\npoints = ["O", "P"]',
                          'type = "slider"\nname = "rail"\npoint = "P"\ndirection = [1.0, 0.0]')
    model = _build(text + '[[outputs]]\nname = "y"\nquantity = "force"\nelement = "rail"\n')
    eq = mbseig.equilibrium(model)
    with pytest.raises(CaseError, match="give direction"):
        mbseig.linearize(model, eq)


def test_frf_cli_errors_are_one_line(tmp_path):
    path = tmp_path / "p.toml"
    path.write_text(PLANAR + '[[inputs]]\nname = "load"\nelement = "load"\n'
                    '[[outputs]]\nname = "y"\nquantity = "position"\npoint = "P"\n'
                    'direction = [1.0, 0.0]\n')
    for argv, message in (
            (["--input", "nope", "--output", "y"], "unknown input 'nope'"),
            (["--input", "load", "--output", "y", "--hz", "5:1:10"], "F1 < F2"),
            (["--input", "load", "--output", "y", "--hz", "a:b"], "F1:F2:N")):
        err = io.StringIO()
        with redirect_stderr(err), redirect_stdout(io.StringIO()):
            assert main(["frf", str(path), *argv]) == 2
        line = err.getvalue().strip()
        assert "\n" not in line and message in line and line.startswith("mbseig: ")


def test_statespace_without_signals_keeps_the_old_form():
    control = pytest.importorskip("control")
    m = mbseig.load_case(CASES / "four_bar.toml")
    lin = mbseig.linearize(m, mbseig.equilibrium(m))
    sys = lin.to_statespace()
    assert sys.ninputs == lin.dof and sys.noutputs == 2 * lin.dof
    assert isinstance(sys, control.StateSpace)


def test_zero_length_spring_output_and_bad_reference_are_refused():
    """A spring sitting at zero length has no line of action and no derivative of its length:
    a length output on it is refused naming the element (was a floating-point error naming
    neither).  A null-space reference naming an unknown coordinate is refused in one line
    (was a Python ValueError)."""
    text = """
schema_version = 1
dimension = 2
[[points]]
name = "O"
position = [0.0, 0.0]
fixed = true
[[points]]
name = "P"
position = [0.0, 0.0]
[[masses]]
point = "P"
mass = 1.0
[[forces]]
type = "spring"
name = "s"
points = ["O", "P"]
stiffness = 10.0
free_length = 0.0
[[outputs]]
name = "y"
quantity = "length"
element = "s"
"""
    model = _build(text)
    eq = mbseig.equilibrium(model)
    with pytest.raises(CaseError, match="zero length at the equilibrium"):
        mbseig.linearize(model, eq)
    m = mbseig.load_case(CASES / "four_bar.toml")
    with pytest.raises(CaseError, match="unknown coordinate 'nope'"):
        mbseig.linearize(m, mbseig.equilibrium(m), reference=["nope"])
