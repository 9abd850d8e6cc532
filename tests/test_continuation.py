"""Continuation in sweeps and boundaries where Re s = 0 (issue 10; docs/design.md,
"Equilibrium": continuation, boundaries).

References (each test names its own): closed-form equilibrium branches (a pendulum under a
horizontal load, tan θ = F/(m g); the one-link column, P L sin θ = k θ with its branch point at
P = k/L), the limit load of a von Mises truss (a fold, from dF/dw = 0 of its closed-form load
curve), the dead point of a driven four-bar (law of cosines), and Ziegler's double pendulum:
undamped flutter at p = 7/2 − √2, and with equal joint dampers c the Hurwitz determinant
c²(41 − 28p + 14c²) of 2s⁴ + 7c s³ + (7 − 2p + c²)s² + 2c s + 1, zero at p = 41/28 + c²/2
(cases/ziegler_pendulum.toml).  Tolerances: 1e-9 relative for the boundaries (the locator's xtol
is 1e-10 of the span), 1e-10 for the branches (the corrector's tolerance is 1e-11 of the model's
size).
"""

import json
import math

import numpy as np
import pytest
from conftest import CASES, write_case

from mbseig.cli import main
from mbseig.studies.sweep import run_sweep

PENDULUM_PUSHED = """
schema_version = 1
title = "pendulum under a horizontal load F at the bob"
dimension = 2
gravity = [0.0, "-g"]
[parameters]
g = 9.81
F = 0.0
[[points]]
name = "O"
position = [0.0, 0.0]
fixed = true
[[points]]
name = "P"
position = [0.0, -1.0]
[[masses]]
point = "P"
mass = 1.0
[[joints]]
type = "distance"
name = "rod"
points = ["O", "P"]
length = 1.0
[[forces]]
type = "force"
name = "push"
point = "P"
vector = ["F", 0.0]
"""

COLUMN = """
schema_version = 1
title = "one-link column: rigid massless bar, base spring k, dead load P at the top"
dimension = 2
[parameters]
k = 1.0
L = 1.0
P = 0.5
[[points]]
name = "O"
position = [0.0, 0.0]
fixed = true
[[points]]
name = "T"
position = [0.0, "L"]
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

VON_MISES = """
schema_version = 1
title = "von Mises truss: two springs to an apex on a vertical guide, load F down"
dimension = 2
[parameters]
F = 0.0
k = 1000.0
a = 1.0
h = 0.3
[[points]]
name = "L"
position = ["-a", 0.0]
fixed = true
[[points]]
name = "R"
position = ["a", 0.0]
fixed = true
[[points]]
name = "T"
position = [0.0, "h"]
[[masses]]
point = "T"
mass = 1.0
[[joints]]
type = "slider"
name = "guide"
point = "T"
direction = [0.0, 1.0]
[[forces]]
type = "spring"
name = "left bar"
points = ["L", "T"]
stiffness = "k"
[[forces]]
type = "spring"
name = "right bar"
points = ["R", "T"]
stiffness = "k"
[[forces]]
type = "force"
name = "load"
point = "T"
vector = [0.0, "-F"]
"""

FOUR_BAR_DRIVEN = """
schema_version = 1
title = "four-bar with a driven crank angle phi: crank 0.5, coupler 0.7, rocker 0.5, ground 1"
dimension = 2
[parameters]
phi = 60.0
[[points]]
name = "A"
position = [0.0, 0.0]
fixed = true
[[points]]
name = "D"
position = [1.0, 0.0]
fixed = true
[[points]]
name = "B"
position = ["0.5*cos(deg(phi))", "0.5*sin(deg(phi))"]
[[points]]
name = "C"
position = [1.1, 0.5]
[[bodies]]
name = "crank"
points = ["A", "B"]
length = 0.5
mass = 1.0
inertia = 0.02
[[bodies]]
name = "coupler"
points = ["B", "C"]
length = 0.7
mass = 1.0
inertia = 0.04
[[bodies]]
name = "rocker"
points = ["D", "C"]
length = 0.5
mass = 1.0
inertia = 0.02
[[joints]]
type = "angle_driver"
name = "crank drive"
bodies = ["ground", "crank"]
angle = "deg(phi)"
"""


def test_pendulum_under_horizontal_load_branch(tmp_path):
    """Each grid point on the branch θ = atan(F/(m g)) (closed form), to 1e-10 rad, every point
    reached on the followed branch (by continuation, or in the line's batch, which reaches each
    point again from the previous one), none solved cold."""
    case = write_case(tmp_path, PENDULUM_PUSHED)
    values = np.linspace(0.0, 40.0, 5)
    res = run_sweep(case, [("F", values)], jobs=1)
    for F, pt in zip(values, res.points[0], strict=True):
        assert pt["statics"] in ("continuation", "batch") and pt["error"] is None
        theta = math.atan2(pt["q"][0], -pt["q"][1])
        assert abs(theta - math.atan(F / 9.81)) < 1e-10
    assert res.boundaries == [] and res.folds == []


def test_column_buckles_onto_its_post_buckled_branch(tmp_path):
    """P from 0.5 k/L to 1.5 k/L: the branch point is located at P = k/L (closed form, 1e-10
    relative), the sweep switches to the buckled branch, stable, where P L sin θ = k θ holds at
    every grid point past it (1e-10); the trivial branch's loss is a divergence boundary."""
    case = write_case(tmp_path, COLUMN)
    values = np.linspace(0.5, 1.5, 6)
    res = run_sweep(case, [("P", values)], jobs=1)
    bps = [f for f in res.folds if f["type"] == "branch point"]
    assert len(bps) == 1 and bps[0]["value"] == pytest.approx(1.0, rel=1e-10)
    assert "switched" in bps[0]["branch"]
    div = [b for b in res.boundaries if b["event"] == "branch point"]
    assert len(div) == 1 and div[0]["kind"] == "divergence" and div[0]["stability"] == "loss"
    for P, pt in zip(values, res.points[0], strict=True):
        theta = math.atan2(pt["q"][0], pt["q"][1])
        if P < 1.0:
            assert abs(theta) < 1e-12
        else:
            assert abs(theta) > 0.3 and P * math.sin(theta) == pytest.approx(theta, rel=1e-10)
            assert pt["static"] == "stable"
    assert res.diagram["variable"] in ("T.x", "T.y")


def test_von_mises_truss_fold(tmp_path):
    """The limit load: F = 2k u (L0/√(a² + u²) − 1) with u the apex height has its maximum
    where (a² + u²)^{3/2} = L0 a² (closed form); the fold is found there (1e-10 relative) as a
    divergence boundary with the branch turning back, and the points past it are on the snapped
    branch (the same closed form, 1e-9 relative)."""
    case = write_case(tmp_path, VON_MISES)
    a, h, k = 1.0, 0.3, 1000.0
    L0 = math.hypot(a, h)
    u = math.sqrt((L0 * a * a) ** (2.0 / 3.0) - a * a)
    F_max = 2 * k * u * (L0 / math.sqrt(a * a + u * u) - 1)
    values = np.linspace(0.0, 20.0, 3)
    res = run_sweep(case, [("F", values)], jobs=1)
    folds = [b for b in res.boundaries if b["event"] == "fold"]
    assert len(folds) == 1
    b = folds[0]
    assert b["value"] == pytest.approx(F_max, rel=1e-10)
    assert b["kind"] == "divergence" and b["stability"] == "loss" and b["branch"] == "turns back"
    for F, pt in zip(values, res.points[0], strict=True):
        y = pt["q"][1]
        load = 2 * k * y * (L0 / math.hypot(a, y) - 1)
        assert load == pytest.approx(F, rel=1e-9, abs=1e-9)
        assert (y > 0) == (F < F_max)  # past the fold: snapped through
    seg = {pt["segment"] for pt in res.points[0]}
    assert seg == {0, 1}


def test_driven_four_bar_turns_at_its_dead_point(tmp_path):
    """Driving the crank past the dead point (coupler and rocker aligned: |B − D| = 0.7 + 0.5,
    so cos φ* = (1.25 − 1.2²)/1, law of cosines): the fold is located there (1e-10 relative),
    the branch turns back into the other assembly mode, and the grid values past it are
    reported as constraints that cannot be satisfied (proved by the position solve)."""
    case = write_case(tmp_path, FOUR_BAR_DRIVEN)
    phi_star = math.degrees(math.acos(1.25 - 1.2 ** 2))
    values = np.linspace(60.0, 120.0, 4)
    res = run_sweep(case, [("phi", values)], jobs=1)
    folds = [f for f in res.folds if f["type"] == "fold"]
    assert len(folds) == 1 and folds[0]["value"] == pytest.approx(phi_star, rel=1e-10)
    assert folds[0]["branch"] == "turns back" and folds[0]["dof"] == 0
    assert res.boundaries == []  # no degree of freedom: no eigenvalue crosses
    for phi, pt in zip(values, res.points[0], strict=True):
        if phi < phi_star:
            assert pt["error"] is None
        else:
            assert "the constraints cannot be satisfied" in pt["error"]
    branch = res.branches[0]
    k = next(i for i, b in enumerate(branch) if b["kind"] == "fold")
    at_100 = next(b["q"][3] for b in branch[:k] if b["p"] == 100.0)
    back = [b for b in branch[k + 1:] if b["p"] < 100.0]
    assert back and all(b["q"][3] < at_100 for b in back)  # C lower: the other assembly mode


ZIEGLER = CASES / "ziegler_pendulum.toml"


def test_ziegler_undamped_flutter_load():
    """Undamped: the eigenvalue pair collides on the imaginary axis at p = 7/2 − √2 (closed
    form, 1e-9 relative) — located by the pair's squared distance, not by δ + tol = 0."""
    res = run_sweep(ZIEGLER, [("p", np.linspace(1.5, 2.5, 3))], jobs=1)
    assert len(res.boundaries) == 1
    b = res.boundaries[0]
    assert b["value"] == pytest.approx(3.5 - math.sqrt(2), rel=1e-9)
    assert b["kind"] == "flutter" and b["stability"] == "loss" and "collision" in b["method"]
    assert b["band"][0] <= b["value"] <= b["band"][1]


@pytest.mark.parametrize("c", [1e-3, 1e-5])
def test_ziegler_damped_boundary_destabilization(c):
    """Equal joint dampers c: the boundary is where Re s = 0, p = 41/28 + c²/2 (Hurwitz, closed
    form above), to 1e-9 relative; with c = 1e-5 that is 41/28 itself to 1e-9, far below the
    undamped 2.0858 (Ziegler's paradox).  The band where the mode is critical is reported
    beside it and contains it."""
    res = run_sweep(ZIEGLER, [("p", np.linspace(1.3, 1.7, 3))], fixed={"c": c}, jobs=1)
    assert len(res.boundaries) == 1
    b = res.boundaries[0]
    assert b["value"] == pytest.approx(41 / 28 + c * c / 2, rel=1e-9)
    assert b["value"] == pytest.approx(41 / 28, rel=1e-9 + c * c)
    assert b["method"].startswith("Re s = 0") and b["band"][0] < b["value"] < b["band"][1]
    assert b["band"][1] - b["band"][0] < 1e-6


def test_two_parameter_continuation_of_the_ziegler_boundary():
    """The damped boundary followed across c ∈ [0.05, 0.4] (two-parameter continuation from the
    first line): every point of the curve on p = 41/28 + c²/2 (closed form), 1e-9 relative."""
    res = run_sweep(ZIEGLER, [("p", np.linspace(1.3, 1.9, 3)), ("c", np.array([0.05, 0.4]))],
                    jobs=1, curve_values=[0.05, 0.2, 0.4])
    assert len(res.curves) == 1
    pts = res.curves[0]["points"]
    assert {0.05, 0.2, 0.4} <= {p["p2"] for p in pts}  # and points where it bends
    for p in pts:
        assert p["value"] == pytest.approx(41 / 28 + p["p2"] ** 2 / 2, rel=1e-9)


def test_sweep_json_interface_extended(tmp_path, capsys):
    """The fixed interface (boundaries with value, kind, stability) is kept and extended with the
    method, band, event and the followed branch; the bifurcation diagram and branch table are
    written.  (The boundary's value is checked against 7/2 − √2 above.)"""
    out = tmp_path / "out"
    assert main(["sweep", str(ZIEGLER), "--param", "p=1.5:2.5:3", "--jobs", "1",
                 "--no-progress", "--json", "--out", str(out), "--diagram", "P2.x"]) == 0
    data = json.loads(capsys.readouterr().out)
    (b,) = data["boundaries"]
    assert {"value", "kind", "stability", "method", "band", "event"} <= set(b)
    assert b["kind"] == "flutter" and b["stability"] == "loss" and b["event"] == "crossing"
    assert data["diagram"]["variable"] == "P2.x" and data["lines"][0]["branch"]
    assert all(p["statics"] in ("continuation", "batch") for p in data["lines"][0]["points"])
    for name in ("bifurcation.png", "branch.csv", "boundaries.csv"):
        assert (out / name).stat().st_size > 0
