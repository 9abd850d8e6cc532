"""The time-domain check cannot be fooled (issue 13, "The time-domain check must not pass a wrong
linearization"): each case runs the right linearization (passes) and a deliberately wrong one
(fails) against the same nonlinear model.

References: the pendulum's closed form ω_n = √(g/l), a horizontal dashpot c giving
ẍ + (c/m)ẋ + (g/l)x = 0, so δ = c/(2m) and ζ = c/(2m ω_n); the two-oscillator linear case's
closed form s = ±iω_k.  Tolerances are the check's own (mbseig/check/modes.py, "Verdict per
mode"): δ and ω to their rtol, widened only to what the run resolves.
"""

import dataclasses
import math

import numpy as np
import pytest
from conftest import CASES, write_case

import mbseig
from mbseig.check import check_modes
from mbseig.studies import analyze

G = 9.81
WN = math.sqrt(G)  # pendulum, l = 1 m


def damped_pendulum(tmp_path, zeta, extra=""):
    """The bundled pendulum with a horizontal dashpot P–W (W 2 m to the side at the bob's height:
    it damps the swing, x, with c = 2ζ m ω_n)."""
    text = (CASES / "pendulum.toml").read_text() + f"""
[[points]]
name = "W"
position = [-2.0, "-l"]
fixed = true

[[forces]]
type = "damper"
name = "dashpot"
points = ["P", "W"]
damping = {2 * zeta * WN!r}
""" + extra
    return analyze(write_case(tmp_path, text, name=f"pendulum_{abs(hash(zeta))}.toml"))


def wrong(a, **changes):
    lin = dataclasses.replace(a.linear, **changes)
    return lin, mbseig.modes(lin.M, lin.P, lin.Q, N=lin.N)


def test_flipped_damping_sign_fails(tmp_path):
    """ζ = 2e-6: predicted δ = ζω_n = 6.26e-6 (closed form).  Right: passes (δ measured to
    1e-9 relative).  Damping flipped in the linearization: predicted δ = −6.26e-6 while the
    nonlinear pendulum decays at +6.26e-6: the run resolves δ far better than their difference
    (resolution ≤ 1e-7), so the check fails — it passed with the old 1e-2·1e-3|s| tolerance."""
    a = damped_pendulum(tmp_path, 2e-6)
    (m,) = check_modes(a.model, a.eq, a.linear, a.modes).modes
    assert m.passed and m.predicted_delta == pytest.approx(2e-6 * WN, rel=1e-9)
    assert abs(m.measured_delta - m.predicted_delta) <= 1e-9 * WN
    lin, md = wrong(a, P=-a.linear.P)
    (m,) = check_modes(a.model, a.eq, lin, md).modes
    assert md.verdict == "unstable" and m.predicted_delta < 0 < m.measured_delta
    assert m.resolution_delta <= 1e-7 and m.passed is False


def test_near_critical_damping_right_passes_wrong_fails(tmp_path):
    """ζ = 1 − 5e-11: ω_d = ω_n√(1 − ζ²) = 3.1e-5 rad/s (closed form) turns 3e-5 rad in the
    3 e-folding times of the run; the modal coordinate amplifies state errors by ω_n/ω_d ≈ 1e5, so
    the run is repeated at a tenth of the amplitude and ω_d is judged to what that resolves (said
    in ``unresolved``): the right linearization passes (it failed at ω error 4.75e-3 > 1e-3), δ
    within 1e-2.  Damping 2 % too high in the linearization (two real roots): fails on δ."""
    a = damped_pendulum(tmp_path, 1 - 5e-11)
    assert a.modes.kind == ["oscillatory"]
    (m,) = check_modes(a.model, a.eq, a.linear, a.modes).modes
    assert m.passed and "ω resolved only to" in m.unresolved
    assert m.amplification > 1e4 and m.measured_delta == pytest.approx(WN, rel=1e-2)
    lin, md = wrong(a, P=1.02 * a.linear.P)
    res = check_modes(a.model, a.eq, lin, md)
    assert md.kind == ["overdamped", "overdamped"] and res.failed == [1, 2]


def test_exactly_critical_damping_is_not_simulated(tmp_path):
    """ζ = 1 exactly (the proportional path's double root −ω_n, defective): no modal coordinate
    isolates a Jordan block; the check says so (skipped, passed None), never a false failure."""
    a = damped_pendulum(tmp_path, 1.0)
    res = check_modes(a.model, a.eq, a.linear, a.modes)
    assert [m.passed for m in res.modes] == [None, None] and res.passed
    assert all("defective" in m.skipped for m in res.modes)


STIFF_ELSEWHERE = """
[[points]]
name = "S"
position = [3.0, 0.0]

[[masses]]
point = "S"
mass = 1.0

[[forces]]
type = "spring"
points = ["O", "S"]
stiffness = 1e7
"""


def test_rigid_probe_uses_the_scale_of_the_mode(tmp_path):
    """The pendulum without Σλ∇²Φ predicts a rigid-body swing; a 1e7 N/m spring on another
    mass (ω = √1e7 ≈ 3162 rad/s, closed form) must not lend it its scale (with it, ω_ref was
    3162 and the pendulum passed): the probe compares the swing's restoring ω_eff = √(g/l) with
    the forces on the bob (ω_ref = √(g/l)) and fails.  The right linearization has the swing at
    √(g/l) and the spring mode at √(k/m) (closed forms, rtol 1e-9)."""
    text = (CASES / "pendulum.toml").read_text() + STIFF_ELSEWHERE
    a = analyze(write_case(tmp_path, text))
    assert a.modes.omega_n[1:] == pytest.approx([WN, math.sqrt(1e7)], rel=1e-9)
    lin = mbseig.linearize(a.model, a.eq, constraint_stiffness=False)
    md = mbseig.modes(lin.M, lin.P, lin.Q, N=lin.N)
    assert md.kind.count("rigid-body") == 1
    res = check_modes(a.model, a.eq, lin, md, indices=[md.kind.index("rigid-body") + 1])
    probe = res.modes[0]
    assert probe.passed is False
    assert probe.probe_omega == pytest.approx(WN, rel=1e-6)
    assert probe.probe_reference == pytest.approx(WN, rel=1e-6)  # not 3162


TWO_SCALES = """
schema_version = 1
kind = "linear"
title = "two decoupled oscillators 1e4 apart"
source = "closed form: s = ±i 1e-3, ±i 10"
[parameters]
k_slow = 1e-6
[matrices]
M = [[1.0, 0.0], [0.0, 1.0]]
Q = [["k_slow", 0.0], [0.0, 100.0]]
"""


def test_run_capped_and_said(tmp_path):
    """Modes at ω = 1e-3 and 10 rad/s (closed form): 20 periods of the slow one would be 1.3e5 s
    of a run stepped by the fast one; the run is capped at max_fast_periods = 200 periods of the
    fastest mode (126 s), says so, and still measures ω to 1e-6.  A wrong slow stiffness (×1.2:
    ω 1.095e-3) fails."""
    a = analyze(write_case(tmp_path, TWO_SCALES))
    res = check_modes(a.model, a.eq, a.linear, a.modes, indices=[1])
    (m,) = res.modes
    assert m.capped and "capped" in m.unresolved and m.duration == pytest.approx(40 * math.pi)
    assert m.passed and m.measured_omega == pytest.approx(1e-3, rel=1e-6)
    Q = np.array(a.linear.Q, float)
    Q[0, 0] *= 1.2
    lin, md = wrong(a, Q=Q)
    assert check_modes(a.model, a.eq, lin, md, indices=[1]).modes[0].passed is False
