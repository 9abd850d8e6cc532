"""Periodic motions of models with frames (3-D rigid bodies): the spatial compound pendulum on a
vertically shaken spherical joint (cases/spatial_pendulum_shaken_pivot.toml) against the Mathieu
equation it reduces to; what a moving joint or point cannot mean is refused; a time-periodic
force beside a moving pivot."""

from __future__ import annotations

import math

import numpy as np
import pytest
from conftest import CASES
from scipy.integrate import solve_ivp
from scipy.special import mathieu_a, mathieu_b

from mbseig.casefile import read_case
from mbseig.cli import main
from mbseig.studies.periodic import periodic_analysis

CASE = CASES / "spatial_pendulum_shaken_pivot.toml"
M, C, J, G, A, W = 1.0, 0.5, 0.02, 9.81, 0.05, 9.0  # the case's parameters
K = M * C / (J + M * C**2)  # m c / J_O


@pytest.fixture(scope="module")
def analysis():
    """The bundled case's periodic analysis (one for the tests that read it)."""
    return periodic_analysis(read_case(CASE))


def _mathieu_multipliers():
    """The swing's multipliers from J_O θ'' + m c (g − A w² cos wt) θ = 0, by integrating its
    fundamental matrix over one period (DOP853, rtol = atol = 1e-13): an independent path."""
    T = 2 * math.pi / W

    def f(t, y):
        Y = y.reshape(2, 2)
        return (np.array([[0.0, 1.0], [-K * (G - A * W**2 * math.cos(W * t)), 0.0]]) @ Y).ravel()

    sol = solve_ivp(f, (0.0, T), np.eye(2).ravel(), method="DOP853", rtol=1e-13, atol=1e-13)
    return np.linalg.eigvals(sol.y[:, -1].reshape(2, 2))


def test_spatial_pendulum_on_a_shaken_pivot_is_the_mathieu_equation(analysis):
    """Two swing planes, each the same Mathieu equation, inside its principal tongue (the
    case's stated boundaries are scipy's characteristic values, 1e-9); the spin about the
    link's axis free.  The four swing multipliers equal the reference pair within mbseig's
    stated bounds plus the reference's integration error (≤ 1e-10 at its tolerance of 1e-13
    over one period).  Before the joint's `at` was read as a pivot driven on the ground, the
    link's attachment moved with the pivot and the multipliers were −1.066 and −0.938."""
    exp = read_case(CASE).data["expected"]
    q = 2 * K * A
    np.testing.assert_allclose(exp["flip_boundaries"],
                               [2 * math.sqrt(K * G / mathieu_a(1, q)),
                                2 * math.sqrt(K * G / mathieu_b(1, q))], rtol=1e-9)
    fl = analysis.floquet
    ref = _mathieu_multipliers()
    assert fl.verdict == exp["verdict"] == "unstable"
    assert np.all(np.isreal(ref)) and min(ref.real) < -1
    swing = np.abs(np.abs(fl.multipliers) - 1) > 1e-3
    got, bounds = fl.multipliers[swing], fl.error_bounds[swing]
    assert got.size == 4
    for mu, b in zip(got, bounds, strict=True):
        assert np.min(np.abs(ref - mu)) <= b + 1e-10


def test_a_fixed_joint_on_the_moving_path_is_the_same_pendulum(tmp_path, analysis):
    """The link's point held on the pivot's path by a `fixed` joint (point, position with t)
    instead of the spherical joint: the same physics by another constraint, the same swing
    multipliers within the two stated bounds."""
    path = tmp_path / "fixed.toml"
    path.write_text(CASE.read_text().replace(
        'type = "spherical"\nbodies = ["ground", "link"]\nat = [0.0, 0.0, "A*cos(w*t)"]',
        'type = "fixed"\npoint = "P"\nposition = [0.0, 0.0, "A*cos(w*t)"]'))
    a, b = analysis.floquet, periodic_analysis(read_case(path)).floquet
    for fl in (a, b):
        assert np.sum(np.abs(np.abs(fl.multipliers) - 1) > 1e-3) == 4
    sa, sb = (np.sort_complex(fl.multipliers[np.abs(np.abs(fl.multipliers) - 1) > 1e-3])
              for fl in (a, b))
    ba = a.error_bounds[np.abs(np.abs(a.multipliers) - 1) > 1e-3].max()
    bb = b.error_bounds[np.abs(np.abs(b.multipliers) - 1) > 1e-3].max()
    assert np.all(np.abs(sa - sb) <= ba + bb)


def _refused(tmp_path, capsys, text, *needles):
    path = tmp_path / "case.toml"
    path.write_text(text)
    assert main(["modes", str(path)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and str(path) in err
    for needle in needles:
        assert needle in err


def test_a_body_on_a_moving_basic_point_is_refused(tmp_path, capsys):
    """The link carried by a fixed point that moves with t would change its own geometry with
    time (its centre of mass is given in the file, the point moves): refused in one line, exit
    code 2, naming the file and the remedy."""
    text = CASE.read_text().replace('position = [0.0, 0.0, "A"]',
                                    'position = [0.0, 0.0, "A*cos(w*t)"]\nfixed = true')
    text = text[:text.index("[[joints]]")]
    _refused(tmp_path, capsys, text, "mass matrix changes with time", "fixed joint")


def test_a_joint_moving_between_two_bodies_or_turning_is_refused(tmp_path, capsys):
    """A moving `at` between two bodies (no ground to drive) and a joint axis that turns with t
    have no reading as a driven pivot: each refused in one line naming the joint."""
    two = CASE.read_text().replace('bodies = ["ground", "link"]', 'bodies = ["link", "ground"]')
    base = two.replace("[[joints]]", """[[bodies]]
name = "other"
mass = 1.0
com = [0.0, 0.0, 2.0]
inertia = [0.1, 0.1, 0.1]
[[joints]]
name = "hold"
type = "weld"
bodies = ["ground", "other"]
at = [0.0, 0.0, 2.0]
[[joints]]""", 1)
    _refused(tmp_path, capsys, base.replace('bodies = ["link", "ground"]',
                                             'bodies = ["link", "other"]'),
             "joints[1] 'pivot'", "between two bodies", "fixed joint")
    turning = CASE.read_text().replace('type = "spherical"', 'type = "revolute"').replace(
        'at = [0.0, 0.0, "A*cos(w*t)"]',
        'at = [0.0, 0.0, "A"]\naxis = ["cos(w*t)", "sin(w*t)", 0.0]')
    _refused(tmp_path, capsys, turning, "joints[0] 'pivot'", "axis uses t")


def test_a_periodic_force_beside_a_moving_pivot(tmp_path):
    """A time-periodic vertical force at the pivot beside its motion (the constant forces and a
    constraint both change with time, a pair that once stopped the analysis with a
    traceback): a verdict with finite bounds."""
    path = tmp_path / "forced.toml"
    path.write_text(CASE.read_text().replace("[expected]", """[[forces]]
name = "push"
type = "force"
point = "P"
vector = [0.0, 0.0, "0.3*cos(w*t)"]

[expected]"""))
    a = periodic_analysis(read_case(path))
    assert a.floquet.verdict == "unstable"
    assert np.all(np.isfinite(a.floquet.error_bounds))


def test_frozen_time_of_the_spatial_pendulum_reads_critical(analysis):
    """At every frozen instant the swing has s = ±i √(k (g − A w² cos wt)), imaginary since
    A w² = 4.05 < g, and the free spin a double s = 0 (closed form): the frozen-time verdict is
    critical and its largest real part reads 0.  It read "unstable" from a real part of 3.6e-8,
    the rounding of the spin's zero pair, under a fixed tolerance of 1e-9 max |s|; each
    eigenvalue is now judged against its own bound (mbseig.modes, DESIGN §6)."""
    from mbseig.studies.periodic_listing import frozen_summary

    out = frozen_summary(analysis)
    assert out["verdict"] == "critical" and out["max_real_part"] == 0.0
    slowest = math.sqrt(K * (G - A * W**2))  # the smallest swing |s| over the period
    assert out["instants"] == 64 and 0.0 < out["bound"] < 1e-3 * slowest  # (the spin's pair)
