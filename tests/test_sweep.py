"""``mbseig sweep``: MAC tracking, boundaries by root finding, identical results on every runner.

References: closed-form eigenvalues of decoupled oscillators (s² + c s + k = 0), and a boundary
located independently by Brent's method on the spectral abscissa of the first-order state matrix
(numpy eigvals), which shares no code with the sweep's QEP solver or tracker.
"""

import json

import numpy as np
import pytest
from scipy.optimize import brentq

from mbseig.cli import main
from mbseig.errors import CaseError
from mbseig.studies.sweep import mac_matrix, parse_range, run_sweep

CROSSING = """
schema_version = 1
kind = "linear"
description = "two decoupled oscillators; the second one's stiffness p sweeps through the first's"
[parameters]
p = 1.0
c = 0.02
[matrices]
M = [[1.0, 0.0], [0.0, 1.0]]
P = [["c", 0.0], [0.0, "c"]]
Q = [[4.0, 0.0], [0.0, "p"]]
[expected]
source = "closed form"
"""

FLUTTER = """
schema_version = 1
kind = "linear"
description = "coupled 2-DOF with a swept (possibly negative) damper c on the first coordinate"
[parameters]
c = 1.0
[matrices]
M = [[1.0, 0.0], [0.0, 2.0]]
P = [["c", 0.0], [0.0, 0.3]]
Q = [[4.0, 1.0], [1.0, 9.0]]
[expected]
source = "state-matrix abscissa"
"""


def _case(tmp_path, text, name):
    p = tmp_path / name
    p.write_text(text)
    return p


def test_parse_range():
    name, v = parse_range("k_a=1e3:2e3:3")
    assert name == "k_a" and v.tolist() == [1000.0, 1500.0, 2000.0]
    for bad in ("k_a=1:2", "k_a=1:2:1", "=1:2:3", "k=a:b:3", "k=1:1:3"):
        with pytest.raises(CaseError):
            parse_range(bad)


def test_mac_tracking_through_a_frequency_crossing(tmp_path):
    """p sweeps 1 → 9 through 4 (not on the grid): the frequency order swaps, but the track that
    starts on the e1 shape stays at s² + c s + 4 = 0 (closed form, 1e-12) at every point."""
    case = _case(tmp_path, CROSSING, "cross.toml")
    res = run_sweep(case, [("p", np.linspace(1.0, 9.0, 5))], jobs=1)
    S = res.tracks[0]
    c = 0.02
    s_e1 = complex(-c / 2, np.sqrt(4 - c * c / 4))
    j = int(np.argmin(np.abs(S[0] - s_e1)))
    np.testing.assert_allclose(S[:, j], s_e1, rtol=1e-12)
    for k, p in enumerate(np.linspace(1.0, 9.0, 5)):  # the other upper-half track follows p
        s_p = complex(-c / 2, np.sqrt(p - c * c / 4))
        assert np.min(np.abs(S[k] - s_p)) < 1e-12 * abs(s_p)
    # sort order would have switched identities: at p = 1 the e1 mode is the higher one
    assert abs(S[0, j].imag) > 1.0 and abs(S[-1, j].imag) < 3.0
    assert res.boundaries == []


def _abscissa(c):
    M = np.diag([1.0, 2.0])
    P = np.diag([c, 0.3])
    Q = np.array([[4.0, 1.0], [1.0, 9.0]])
    A = np.block([[np.zeros((2, 2)), np.eye(2)],
                  [-np.linalg.solve(M, Q), -np.linalg.solve(M, P)]])
    return np.linalg.eigvals(A).real.max()


def test_boundary_matches_independent_root(tmp_path):
    case = _case(tmp_path, FLUTTER, "flutter.toml")
    res = run_sweep(case, [("c", np.linspace(1.0, -1.0, 5))], jobs=1, xtol_rel=1e-12)
    c_ref = brentq(_abscissa, 1.0, -1.0, xtol=1e-14)
    assert len(res.boundaries) == 1
    b = res.boundaries[0]
    assert b["stability"] == "loss" and b["kind"] == "flutter" and b["converged"]
    # xtol 2e-12 plus the offset of the root of δ + tol from δ = 0 (tol ≈ 1e-12 |s|)
    assert b["value"] == pytest.approx(c_ref, abs=1e-9)
    assert b["value"] < 0  # the loss needs negative damping


def test_identical_on_every_runner(tmp_path):
    """Serial, local processes and a Dask LocalCluster give bit-identical JSON
    (dask[distributed] is part of the test extra)."""
    case = _case(tmp_path, FLUTTER, "flutter.toml")
    axes = [("c", np.linspace(1.0, -1.0, 4))]
    serial = json.dumps(run_sweep(case, axes, jobs=1).to_json())
    procs = json.dumps(run_sweep(case, axes, jobs=2).to_json())
    assert serial == procs
    import distributed

    with (distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=False,
                                   dashboard_address=None) as cluster,
          distributed.Client(cluster) as client):
        dask = run_sweep(case, axes, scheduler=client)
        assert dask.runner == "dask"
        assert json.dumps(dask.to_json()) == serial


def test_cli_two_parameter_map(tmp_path, capsys):
    case = _case(tmp_path, FLUTTER, "flutter.toml")
    out = tmp_path / "out"
    rc = main(["sweep", str(case), "--param", "c=1:-1:4", "--param", "c=0.5", "--out", str(out)])
    assert rc == 2  # swept and fixed at once: a one-line error
    # a second (dummy-free) axis: sweep c and the damper on nothing else → use Q via a parameter
    text = FLUTTER.replace("c = 1.0", "c = 1.0\nk2 = 9.0").replace("[1.0, 9.0]", '[1.0, "k2"]')
    case2 = _case(tmp_path, text, "map.toml")
    rc = main(["sweep", str(case2), "--param", "c=1:-1:3", "--param", "k2=8:10:2",
               "--out", str(out), "--jobs", "1"])
    assert rc == 0
    for name in ("sweep.json", "tracks.csv", "boundaries.csv", "root_locus.png",
                 "modes_vs_parameter.png", "stability_map.png"):
        assert (out / name).stat().st_size > 0
    data = json.loads((out / "sweep.json").read_text())
    assert len(data["lines"]) == 2 and len(data["boundaries"]) == 2
    for b in data["boundaries"]:  # each located root agrees with the independent abscissa root
        assert b["fixed"]["k2"] in (8.0, 10.0)
    err = capsys.readouterr().err
    assert "[" not in err.replace("mbseig:", "")  # no progress bar when stderr is not a terminal


def test_mac_matrix_invariant_to_phase():
    rng = np.random.default_rng(0)
    a = rng.standard_normal((5, 2)) + 1j * rng.standard_normal((5, 2))
    np.testing.assert_allclose(np.diag(mac_matrix(a, a * np.exp(0.7j))), 1.0, rtol=1e-14)


CONTINUED = """
schema_version = 1
title = "pendulum under a horizontal load (a branch followed by continuation)"
dimension = 2
gravity = [0.0, -9.81]
[parameters]
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
points = ["O", "P"]
length = 1.0
[[forces]]
type = "force"
point = "P"
vector = ["F", 0.0]
[expected]
source = "tan θ = F/(m g)"
"""


def test_continuation_identical_in_process_and_on_processes(tmp_path):
    """Lines followed by continuation are pure functions too: one line per F-sweep and two lines
    (a second axis) give bit-identical JSON serially and on two processes."""
    case = _case(tmp_path, CONTINUED, "pushed.toml")
    axes = [("F", np.linspace(0.0, 10.0, 3))]
    serial = json.dumps(run_sweep(case, axes, jobs=1).to_json())
    procs = json.dumps(run_sweep(case, axes, jobs=2).to_json())
    assert serial == procs
    assert all(p["statics"] in ("continuation", "batch")
               for p in json.loads(serial)["lines"][0]["points"])

