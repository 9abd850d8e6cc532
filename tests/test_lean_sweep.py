"""The lean sweep path gives the numbers of the general one (issue 28: sweeps at hundreds of
points a second).

Reference throughout: the general path of the same sweep — the case built, and its
inverse-statics command resolved, at every value (``run_sweep(..., lean=False)``, and the
boundary searches with :meth:`ScalarUpdate.make` disabled) — an independent computation of the
same quantities.  Tolerances: the lean model is the built one element by element (bitwise, by
pickled content); a held actuator tension moves the free length by rounding only, so the
eigenvalues agree to 1e-12 relative; verdicts, tracked kinds and boundary kinds are equal, and
boundary values agree to the sweep's own xtol.
"""

from __future__ import annotations

import dataclasses
import pickle
import warnings

import numpy as np
import pytest

from mbseig.casefile import read_case
from mbseig.casefile.element_readers import MassUpdate, ScalarUpdate
from mbseig.errors import MbseigError
from mbseig.studies import run_sweep
from mbseig.statics.inverse import held_tension
from mbseig.studies.continuation import family_maker

from conftest import CASES

DEVICE = CASES / "hand_device.toml"


@pytest.fixture(scope="module")
def device():
    return read_case(DEVICE)


def _content(model):
    """Everything a model is built from (its init fields), as bytes."""
    return pickle.dumps([getattr(model, f.name) for f in dataclasses.fields(model) if f.init])


@pytest.mark.parametrize("config, axis, values, fixed", [
    (None, "k_a", [800.0, 1000.5, 1200.0], {"c_a": 5.0}),      # a spring constant
    ("C4", "f", [0.0, 0.7, 2.5], {}),                          # a follower load's magnitude
    ("C4", "damping_scale", [1.0, 0.1, 0.0], {}),              # four dampers through one scale
    ("C2", "c_a", [1.0, -5.0, -20.0], {"k_a": 5000.0}),        # an active (negative) damper
])
def test_scalar_update_equals_build(device, config, axis, values, fixed):
    """Reference: the full build at each value; equal in every field (pickled bytes)."""
    m0 = device.build(config, **fixed, **{axis: values[0]})
    upd = ScalarUpdate(device.data, config, fixed, axis, m0)
    assert upd.reason is None and upd.updates
    for v in values:
        assert _content(upd.make(v)) == _content(device.build(config, **fixed, **{axis: v}))


@pytest.mark.parametrize("axis, where", [("mcp_target", "points"), ("g", "gravity"),
                                         ("hand_length", "points")])
def test_geometry_parameters_fall_back_to_the_build(device, axis, where):
    """A parameter that moves the geometry (or gravity) is built at every value, and says why."""
    m0 = device.build(None, **{axis: device.build().parameters[axis]})
    upd = ScalarUpdate(device.data, None, {}, axis, m0)
    assert upd.make(1.0) is None
    assert upd.reason.startswith(f"{axis} enters {where}")
    make, state = family_maker(device, None, {}, axis)
    make(device.build().parameters[axis])
    assert state["model"].startswith("built at every value (")


def test_bad_value_gives_the_build_message(device):
    """A negative stiffness at one value: the lean family raises the build's own one-line
    error (file and element named), as the general path does."""
    make, _ = family_maker(device, None, {}, "k_a")
    make(1000.0)
    with pytest.raises(MbseigError) as lean:
        make(-5.0)
    with pytest.raises(MbseigError) as general:
        device.build(None, k_a=-5.0)
    assert lean.value.one_line() == general.value.one_line()
    assert "hand_device.toml" in lean.value.one_line() and "actuator" in lean.value.one_line()


def test_held_tension_only_for_the_same_elements(device):
    """The held tension is refused (None: the command is resolved) when an element other
    than the commanded spring differs from the resolved neighbour's."""
    make, state = family_maker(device, "C4", {}, "k_a")
    for v in (900.0, 1000.0, 1100.0):
        make(v)
    prev = state["last"]
    assert held_tension(device.build("C4", k_a=1050.0), prev) is None  # other element objects
    upd = state["lean"]
    m = upd.make(1050.0)
    r = held_tension(m, prev)
    assert r is not None and r.drivers[0]["iterations"] == 0
    k = [f.name for f in m.forces].index("forces[3] 'actuator'")
    # independent: T = k (l − l0) of the resolved neighbour equals that of the held setting
    t_prev = prev.drivers[0]["sets"][0]["tension"]
    assert r.drivers[0]["sets"][0]["tension"] == pytest.approx(t_prev, rel=1e-12)
    assert r.forces[k].stiffness == 1050.0
    # another stiffness: refused
    other = dataclasses.replace(m, forces=tuple(
        dataclasses.replace(f, stiffness=2 * f.stiffness) if f.name == "forces[0] 'MCP'" else f
        for f in m.forces))
    assert held_tension(other, prev) is None
    # another follower load or damping value: taken, since neither enters the device at rest
    # (the command is resolved without follower loads: hand_device.toml), and it sets the free
    # length the resolve finds on its own (to its tolerance, 1e-12 of the effort)
    from mbseig.statics import resolve

    loads = dataclasses.replace(m, forces=tuple(
        dataclasses.replace(f, magnitude=2.0) if hasattr(f, "magnitude") else
        dataclasses.replace(f, damping=3 * f.damping) if f.name == "forces[1] 'PIP'" else f
        for f in m.forces))
    got = held_tension(loads, prev)
    assert got is not None
    own = resolve(loads)
    assert got.forces[k].free_length == pytest.approx(own.forces[k].free_length, rel=1e-10)


def _sweeps(device, monkeypatch, config, axes):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        lean = run_sweep(device, axes, config=config, progress=False, jobs=1)
        with monkeypatch.context() as mp:
            mp.setattr(ScalarUpdate, "make", lambda self, p: None)
            mp.setattr(MassUpdate, "make", lambda self, p: None)
            mp.setattr(MassUpdate, "make_many", lambda self, values: [None] * len(values))
            general = run_sweep(device, axes, config=config, progress=False, jobs=1, lean=False)
    return lean, general


def _compare(lean, general):
    assert len(lean.points) == len(general.points)
    worst = 0.0
    for la, ga in zip(lean.points, general.points, strict=True):
        for a, b in zip(la, ga, strict=True):
            assert a.get("error") == b.get("error")
            assert a["verdict"] == b["verdict"] and a["static"] == b["static"]
            sa, sb = np.sort_complex(a["eigenvalues"]), np.sort_complex(b["eigenvalues"])
            assert sa.shape == sb.shape
            worst = max(worst, float(np.max(np.abs(sa - sb) / np.abs(sb))))
    assert worst <= 1e-12
    for S, T in zip(lean.tracks, general.tracks, strict=True):
        assert S.shape == T.shape
        np.testing.assert_allclose(S, T, rtol=1e-12, atol=0)
    xtol = general.tolerances["xtol"]
    assert [(b["kind"], b["stability"], b["line"]) for b in lean.boundaries] == \
        [(b["kind"], b["stability"], b["line"]) for b in general.boundaries]
    for a, b in zip(lean.boundaries, general.boundaries, strict=True):
        assert abs(a["value"] - b["value"]) <= xtol


def test_device_stiffness_sweep_lean_equals_general(device, monkeypatch):
    """The device sweep along k_a (the commanded actuator's stiffness: the tension held)."""
    lean, general = _sweeps(device, monkeypatch, None,
                            [("k_a", np.linspace(800.0, 1200.0, 8)), ("c_a", [5.0, 9.0])])
    assert lean.records[0]["model"] == "built once, force scalars updated at each value"
    assert "tension held" in lean.records[0]["commands"]
    assert general.records[0]["commands"] == "resolved at every value"
    _compare(lean, general)


def test_device_load_sweep_lean_equals_general(device, monkeypatch):
    """C4: the tendon load through its flutter boundary (located by both paths)."""
    lean, general = _sweeps(device, monkeypatch, "C4",
                            [("f", np.linspace(0.0, 2.5, 9)), ("damping_scale", [1.0])])
    assert general.boundaries, "the C4 line crosses its flutter boundary"
    _compare(lean, general)


PENDULUM = CASES / "spatial_double_pendulum.toml"


@pytest.mark.parametrize("axis, factors", [("m1", [0.5, 1.0, 2.0]), ("m2", [0.7, 1.3]),
                                           ("J1", [0.8, 1.25]), ("Ja", [0.5, 1.5])])
def test_mass_update_equals_build(axis, factors):
    """A spatial case along a body's mass or inertia: the mass matrix and the gravity load
    formed again from the bodies' parts equal the full build in every field (pickled bytes)."""
    spec = read_case(PENDULUM)
    v0 = float(spec.build().parameters[axis])
    m0 = spec.build(None, **{axis: v0})
    upd = MassUpdate(spec.data, None, {}, axis, m0)
    assert upd.reason is None and upd.updates
    for f in factors:
        assert _content(upd.make(f * v0)) == _content(spec.build(None, **{axis: f * v0}))
    # the models of many values formed together: the same bytes
    many = upd.make_many([f * v0 for f in factors])
    for f, m in zip(factors, many, strict=True):
        assert _content(m) == _content(spec.build(None, **{axis: f * v0}))


@pytest.mark.parametrize("axis, where", [("l1", "bodies[1].com[2]"), ("g", "gravity[2]")])
def test_mass_update_declines_geometry(axis, where):
    spec = read_case(PENDULUM)
    upd = MassUpdate(spec.data, None, {}, axis, spec.build())
    assert upd.reason == f"{axis} enters {where}" and upd.make(1.0) is None


def test_mass_update_bad_value_gives_the_build_message():
    """A triangle inequality broken at one value: the lean family raises the build's own
    one-line error."""
    spec = read_case(PENDULUM)
    make, state = family_maker(spec, None, {}, "Ja")
    make(0.003)
    assert state["model"] == "built once, body masses and inertias updated at each value"
    with pytest.raises(MbseigError) as lean:
        make(1.0)
    with pytest.raises(MbseigError) as general:
        spec.build(None, Ja=1.0)
    assert lean.value.one_line() == general.value.one_line()
    # the models of a line formed together: the batch declines, the value alone raises the same
    assert make.many([0.003, 0.004, 1.0]) is None
    assert [m is not None for m in make.many([0.003, 0.004])] == [True, True]


def test_pendulum_mass_sweep_lean_equals_general(monkeypatch):
    lean, general = _sweeps(read_case(PENDULUM), monkeypatch, None,
                            [("m1", np.linspace(0.5, 3.0, 8)), ("l1", [0.5, 0.8])])
    assert lean.records[0]["model"] == "built once, body masses and inertias updated at each value"
    _compare(lean, general)
