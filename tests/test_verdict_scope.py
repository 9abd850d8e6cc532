"""The verdict counts only modes that are not rigid-body by construction (DESIGN §6).

References: the Whipple bicycle benchmark (Meijaard, Papadopoulos, Ruina & Schwab 2007, Proc. R.
Soc. A 463, Table 2 and section 6: weave speed 4.292382536341 m/s, capsize speed
6.024262015388 m/s, self-stable between); closed forms of the small models below.  The rigid-body
directions come from the model's structure (mbseig.model.symmetry, the motion's cyclic
directions), and a zero that is not declared (a divergence about to start) stays in the verdict.
"""

import json

import numpy as np
import pytest
from conftest import CASES

import mbseig
from mbseig.cli import main
from mbseig.studies.pipeline import as_spec
from mbseig.studies.steady_modes import analyze_steady

BICYCLE = CASES / "whipple_bicycle.toml"
V_WEAVE, V_CAPSIZE = 4.292382536341, 6.024262015388  # Meijaard et al. 2007
STRAIGHT = ["position along the motion", "lateral position", "heading", "speed along the motion"]


@pytest.mark.parametrize("v,verdict", [(3.0, "unstable"), (5.0, "stable"), (7.0, "unstable"),
                                       (6.02426201538837, "critical")])
def test_bicycle_verdict_at_its_speeds(v, verdict, capsys):
    assert main(["modes", str(BICYCLE), "--param", f"v={v!r}", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["verdict"] == verdict
    declared = [m["rigid_body"] for m in out["modes"] if m.get("rigid_body")]
    assert declared == STRAIGHT  # the same four directions at every speed, named
    assert "4 rigid-body modes (s = 0) by construction not counted" in out["verdict_scope"]
    near_zero = [m for m in out["modes"] if m["kind"] == "rigid-body"]
    if verdict == "critical":
        # a fifth eigenvalue sits at 0 (within its bound) and is counted: the capsize
        extra = [m for m in near_zero if not m.get("rigid_body")]
        assert len(extra) == 1 and extra[0]["stability"] == "critical"
        assert abs(extra[0]["eigenvalue"][0]) <= extra[0]["tolerance"]
    else:
        assert len(near_zero) == 4


def test_bicycle_sweep_finds_weave_and_capsize(tmp_path, capsys):
    args = ["sweep", str(BICYCLE), "--param", "v=0:10:11", "--json", "--no-progress", "--out",
            str(tmp_path)]
    assert main(args) == 0
    out = json.loads(capsys.readouterr().out)
    got = {b["kind"]: b for b in out["boundaries"]}
    assert set(got) == {"flutter", "divergence"}, out["boundaries"]
    assert abs(got["flutter"]["value"] - V_WEAVE) <= 1e-5  # the tolerance
    assert got["flutter"]["stability"] == "recovery"
    assert abs(got["divergence"]["value"] - V_CAPSIZE) <= 1e-5
    assert got["divergence"]["stability"] == "loss"


def test_declared_directions_are_invariant_and_exact():
    """The four directions are an invariant subspace of the pencil to rounding (their
    eigenvalues all 0: J nilpotent), recorded as the residual."""
    a = analyze_steady(as_spec(BICYCLE), params={"v": "5.0"})
    assert list(a.cyclic.names) == STRAIGHT
    assert a.cyclic.residual <= 1e-11
    assert np.allclose(np.linalg.matrix_power(a.cyclic.J, 4), 0.0, atol=1e-10)


def test_steady_turn_declares_heading_and_the_in_plane_pair():
    """In a steady turn the heading is s = 0 and the two in-plane positions s = ±i r (the
    turning frame: a turn about a shifted centre), both left out; the rolling disk's own zeros
    (the family of steady turns) are not declared and count."""
    a = analyze_steady(as_spec(CASES / "rolling_disk_turn.toml"))
    r = a.motion.yaw_rate
    rows = [m for m in a.modes if m.get("rigid_body")]
    assert sorted(m["omega_d"] for m in rows) == pytest.approx([0.0, abs(r)], rel=1e-12, abs=0)
    assert a.verdict == "critical"  # undamped: the ±1.3048i lean pair is critical by itself


# ---- at rest: directions from the structure -----------------------------------------------------
@pytest.mark.parametrize("case,expected", [
    ("rigid_rotor", ["rotor: rotation about the line through (0.3, 0, 0) along (1, 0, 0)"]),
    ("spherical_pendulum", ["bob: rotation about the line through (0, 0, -0.8) along (0, 0, 1)"]),
    ("spatial_double_pendulum", ["upper: spin about (0, 0, 1)", "lower: spin about (0, 0, 1)"]),
    ("chain_free_free", ["the whole model: translation along (1, 0, 0)"]),
    ("four_bar", []),
    ("hand_device", []),
    ("double_pendulum", []),
])
def test_rest_rigid_directions(case, expected):
    a = mbseig.analyze(CASES / f"{case}.toml")
    md = a.modes
    declared = [r for r in md.rigid_body if r]
    assert declared == expected
    for k, r in enumerate(md.rigid_body):
        if r:  # a declared mode is one the solver found at 0, and its vector is exact
            assert md.kind[k] == "rigid-body" and md.stability[k] == "critical"
            x = md.vectors[:, k]
            Q = np.asarray(a.linear.Q)
            assert np.linalg.norm(Q @ x) <= 1e-11 * np.linalg.norm(Q) * np.linalg.norm(x)


INVERTED = """
schema_version = 1
title = "inverted pendulum held by a horizontal spring"
dimension = 2
gravity = [0.0, "-g"]
[parameters]
m = 1.0
l = 1.0
g = 9.81
k = 9.81
[[points]]
name = "O"
position = [0.0, 0.0]
fixed = true
[[points]]
name = "W"
position = [1.0, "l"]
fixed = true
[[points]]
name = "P"
position = [0.0, "l"]
[[masses]]
point = "P"
mass = "m"
[[joints]]
type = "distance"
name = "rod"
points = ["O", "P"]
length = "l"
[[forces]]
type = "spring"
name = "holder"
points = ["P", "W"]
stiffness = "k"
"""


@pytest.mark.parametrize("k,verdict", [(9.81, "critical"), (9.0, "unstable"), (11.0, "critical")])
def test_a_divergence_about_to_start_is_not_declared(tmp_path, k, verdict):
    """The inverted pendulum with a horizontal spring has Q = k − m g/l (closed form): at k =
    m g / l the swing is a null vector of Q by a cancellation of the spring against gravity,
    not by construction.  The spring resists the swing on its own, so nothing is declared and
    the zero decides the verdict as critical; below it the pendulum falls (unstable)."""
    path = tmp_path / "inverted.toml"
    path.write_text(INVERTED)
    a = mbseig.analyze(path, params={"k": k})
    md = a.modes
    assert not any(md.rigid_body)
    assert md.verdict == verdict
    assert md.omega_n[0] == pytest.approx(np.sqrt(abs(k - 9.81)), abs=1e-6)


def test_restrained_spin_is_not_declared():
    """rigid_rotor with a torsional stiffness in its first bearing: the spin is resisted by that
    element alone, so it is not a rigid-body direction (and no eigenvalue is at 0)."""
    spec = as_spec(CASES / "rigid_rotor.toml")
    spec.data["forces"][0]["stiffness"][3] = 1e3
    model = spec.build(None)
    eq = mbseig.equilibrium(model)
    lin = mbseig.linearize(model, eq)
    assert len(lin.rigid()) == 0
    assert "rigid-body" not in mbseig.modes(lin).kind


def test_raw_matrices_with_declared_directions():
    """modes(M, P, Q, rigid=D): a free mass (s = 0 double) declared is left out; the same
    zero undeclared makes the verdict critical; a model with no other mode is critical."""
    M, P = np.eye(2), np.diag([0.0, 1.0])
    Q = np.diag([0.0, 4.0])  # a free coordinate and a damped oscillator (stable)
    md = mbseig.modes(M, P, Q, rigid=np.array([[1.0], [0.0]]))
    assert md.verdict == "stable" and md.rigid_body.count(None) == len(md) - 1
    assert mbseig.modes(M, P, Q).verdict == "critical"
    only = mbseig.modes(np.eye(1), np.zeros((1, 1)), np.zeros((1, 1)), rigid=np.eye(1))
    assert only.verdict == "critical" and "no other mode" in only.verdict.rigid_scope
