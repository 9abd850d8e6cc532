"""The command line on every 3-D case (modes, check, sweep, report), 3-D point-mass cases as
before, and bad 3-D input: one line naming the file and the element, exit code 2."""

import json
import warnings

import pytest
from conftest import CASES, write_case

from mbseig.cli import main

SPATIAL = ["spherical_pendulum", "spatial_double_pendulum", "rssr_four_bar", "heavy_top",
           "rigid_rotor"]


@pytest.fixture(autouse=True)
def quiet():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # statically unstable tops, etc.
        yield


@pytest.mark.parametrize("name", SPATIAL)
def test_modes_and_check_on_every_spatial_case(name, capsys):
    path = CASES / f"{name}.toml"
    assert main(["modes", str(path), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["n_redundant"] == 0 and out["verdict"] == "critical"
    # every mode of the case (rigid-body modes by the static probe) against the nonlinear model
    assert main(["check", str(path), "--periods", "3", "--json"]) == 0
    res = json.loads(capsys.readouterr().out)
    assert res["passed"] and all(m["passed"] for m in res["modes"])


@pytest.mark.parametrize("name", SPATIAL)
def test_report_on_every_spatial_case(name, tmp_path):
    assert main(["report", str(CASES / f"{name}.toml"), "--out", str(tmp_path), "--no-check",
                 "--no-animations"]) == 0
    text = (tmp_path / "report.md").read_text()
    assert "verdict: critical" in text


def test_sweep_over_the_speed_gives_the_campbell_diagram(tmp_path, capsys):
    """mbseig sweep over a rotor's speed: Campbell diagram and critical speeds with their whirl,
    against the closed forms of cases/rigid_rotor.toml (Genta 2005 §4), 1e-9 relative (Brent
    to xtol 1e-10 of the span)."""
    from test_spatial_rotor import critical_speeds

    import mbseig

    out = tmp_path / "sweep"
    path = CASES / "rigid_rotor.toml"
    assert main(["sweep", str(path), "--param", "Omega=0:800:9", "--jobs", "1", "--no-progress",
                 "--json", "--out", str(out)]) == 0
    res = json.loads(capsys.readouterr().out)
    expected = critical_speeds(mbseig.load_case(path).parameters)
    got = [(c["value"], c["whirl"]) for c in res["critical_speeds"]]
    assert [w for _, w in got] == [w for _, w in expected]
    assert [v for v, _ in got] == pytest.approx([v for v, _ in expected], rel=1e-9)
    assert (out / "campbell.png").exists() and len(res["campbell"]["tracks"]) == 6


BODY = """
schema_version = 1
dimension = 3
gravity = [0.0, 0.0, -9.81]
[[bodies]]
name = "b"
mass = 1.0
com = [0.0, 0.0, -1.0]
inertia = {inertia}
[[bodies]]
name = "c"
mass = 1.0
com = [0.0, 0.0, -2.0]
inertia = [0.1, 0.1, 0.1]
[[joints]]
name = "j"
type = "{kind}"
bodies = ["ground", "b"]
at = [0.0, 0.0, 0.0]
{extra}
"""

BAD = {
    "zero axis": ({"kind": "revolute", "extra": "axis = [0.0, 0.0, 0.0]"},
                  "joints[0] 'j': axis must not be zero"),
    "non-unit axis": ({"kind": "revolute", "extra": "axis = [1.0, 1.0, 0.0]"},
                      "joints[0] 'j': axis must be a unit vector, got |axis| = 1.41421356237"),
    "non-unit normal": ({"kind": "point_on_plane", "extra": "normal = [0.0, 0.0, 2.0]"},
                        "joints[0] 'j': normal must be a unit vector"),
    "universal axes not perpendicular": (
        {"kind": "universal", "extra": "axes = [[1.0, 0.0, 0.0], [0.6, 0.8, 0.0]]"},
        "joints[0] 'j': the axes of a universal joint must be perpendicular"),
    "revolute axes that do not coincide": (
        {"kind": "revolute", "extra": 'axis = [1.0, 0.0, 0.0]\n[[joints]]\ntype = "revolute"\n'
                                    'bodies = ["b", "ground"]\nat = [0.0, 0.0, -1.0]\n'
                                    'axis = [1.0, 0.0, 0.0]'},
        "joints[1]: its axis does not coincide with that of joints[0] 'j'"),
    "unknown joint": ({"kind": "hinge", "extra": ""}, "joints[0] 'j': unknown joint type 'hinge'"),
    "typo in a joint": ({"kind": "spherical", "extra": "axis = [0.0, 0.0, 1.0]"},
                        "joints[0] 'j': unknown field 'axis'"),
    "bushing matrix size": (
        {"kind": "spherical", "extra": '[[forces]]\ntype = "bushing"\nbodies = ["b", "c"]\n'
                                     'at = [0.0, 0.0, -1.5]\nstiffness = [1.0, 2.0]'},
        "forces[0]: stiffness must be 6 numbers or a 6x6 matrix"),
    "rotor on an unknown body": (
        {"kind": "spherical", "extra": '[[forces]]\ntype = "rotor"\nbody = "d"\n'
                                     'axis = [0.0, 0.0, 1.0]\npolar_inertia = 1.0\nspeed = 10.0'},
        "forces[0]: unknown body 'd'"),
    "torsional on a spherical joint": (
        {"kind": "spherical",
         "extra": '[[forces]]\ntype = "torsional"\njoint = "j"\nstiffness = 1.0'},
        "forces[0]: joint 'j' is not a revolute or cylindrical joint declared before"),
}
BAD_INERTIA = {
    "not positive definite": ("[1.0, -1.0, 1.0]",
                              "bodies[0] 'b': inertia tensor must be positive definite"),
    "triangle inequality": ("[1.0, 1.0, 3.0]",
                            "bodies[0] 'b': principal moments 1, 1, 3 violate the triangle"),
    "not symmetric": ("[[1.0, 0.2, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]",
                      "bodies[0] 'b': inertia tensor must be symmetric"),
    "wrong shape": ("[1.0, 2.0]", "bodies[0] 'b': inertia must be 3 numbers or a 3x3 matrix"),
}


@pytest.mark.parametrize("case", sorted(BAD))
def test_bad_spatial_joints_and_forces(case, tmp_path, capsys):
    fields, message = BAD[case]
    path = write_case(tmp_path, BODY.format(inertia="[0.1, 0.1, 0.1]", **fields))
    assert main(["modes", str(path)]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and err.startswith(f"mbseig: {path}: ") and message in err, err


@pytest.mark.parametrize("case", sorted(BAD_INERTIA))
def test_bad_inertia(case, tmp_path, capsys):
    inertia, message = BAD_INERTIA[case]
    path = write_case(tmp_path, BODY.format(inertia=inertia, kind="spherical", extra=""))
    assert main(["modes", str(path)]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and message in err, err


# --- whirl in modes --json ---
def test_modes_json_whirl(capsys):
    """modes --json: "whirl" per mode of a rotor case (mbseig.model.spatial_whirl; the values
    are checked against the mode shapes in tests/test_spatial_rotor.py), none without a rotor."""
    assert main(["modes", str(CASES / "rigid_rotor.toml"), "--json"]) == 0
    modes = json.loads(capsys.readouterr().out)["modes"]
    assert [m["whirl"] for m in modes] == ["none", "none", "mixed", "mixed", "backward", "forward"]
    assert main(["modes", str(CASES / "rssr_four_bar.toml"), "--json"]) == 0
    assert all("whirl" not in m for m in json.loads(capsys.readouterr().out)["modes"])
