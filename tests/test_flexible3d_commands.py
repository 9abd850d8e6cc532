"""`mbseig frf` and `mbseig report` on a 3-D flexible rotor (Friswell's overhung rotor, the
case of cases/overhung_rotor_friswell.toml with two Euler–Bernoulli elements, an axial and
torsional stop at the first bearing, a force input and a position output at the disk, and a
report sweep over the speed), and the beams drawn as curves."""

import json
import math
import re
import warnings
from pathlib import Path

import numpy as np
import pytest

from conftest import write_case
from mbseig import load_case
from mbseig.cli import main

CASES = Path(__file__).resolve().parents[1] / "cases"

EXTRA = """
[[inputs]]
name = "Fz"
point = "shaft.disk"
direction = [0.0, 0.0, 1.0]

[[outputs]]
name = "z_disk"
quantity = "position"
point = "shaft.disk"
direction = [0.0, 0.0, 1.0]

[[report.studies]]
title = "speed sweep"
sweep = "Omega"
range = [0.0, 800.0]
count = 3

"""


def small_rotor(tmp_path):
    text = (CASES / "overhung_rotor_friswell.toml").read_text()
    text = (text.replace("elements = 6", "elements = 2")
                .replace('theory = "timoshenko"', 'theory = "euler-bernoulli"')
                .replace('stiffness = [0.0, "k", "k", 0.0, 0.0, 0.0]\n',
                         'stiffness = ["k", "k", "k", 1e4, 0.0, 0.0]\n', 1))
    # the case's [expected] values are those of its own mesh: left out
    return write_case(tmp_path, text.split("[expected]")[0] + EXTRA)


def test_frf_on_a_3d_flexible_rotor(tmp_path, capsys):
    """The DC gain z/F at the overhung disk equals the static deflection of an Euler–Bernoulli
    beam on two spring supports (exact for cubic elements under a nodal load): the overhang's
    bending P b²(a+b)/(3EI) plus the rigid motion on the springs (w₁ = −P b/(a k),
    w₂ = P (a+b)/(a k)), asserted 1e-9 relative; every pole is an eigenvalue of `mbseig modes`
    (1e-8 relative)."""
    path = small_rotor(tmp_path)
    assert main(["frf", str(path), "--input", "Fz", "--output", "z_disk", "--hz", "1:200:20",
                 "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    a, b, k, E, d = 1.0, 0.5, 1e7, 211e9, 0.05
    EI = E * math.pi * d**4 / 64
    w1, w2 = -b / (a * k), (a + b) / (a * k)
    dc = b**2 * (a + b) / (3 * EI) + w1 + (w2 - w1) * (a + b) / a
    assert abs(out["dc_gain"] - dc) <= 1e-9 * abs(dc)
    assert len(out["freq_hz"]) == 20 and len(out["response"]) == 20
    assert main(["modes", str(path), "--json"]) == 0
    modes = json.loads(capsys.readouterr().out)
    eig = np.array([complex(*m["eigenvalue"]) for m in modes["modes"]])
    eig = np.concatenate([eig, eig.conj()])
    for re_, im in out["poles"]:
        p = complex(re_, im)
        assert np.min(np.abs(eig - p)) <= 1e-8 * max(abs(p), 1.0)


def test_report_on_a_3d_flexible_rotor(tmp_path):
    """The report of the rotor: its speed sweep study adds the Campbell diagram, the critical
    speeds (at each, the mode's frequency equals the speed: ω = Ω to the printed 6 digits) and
    the unbalance response with its figures; the mode shapes draw the lowest 6 modes."""
    from mbseig.studies.report_data import write_report

    path = small_rotor(tmp_path)
    out = tmp_path / "rep"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        md, _ = write_report(path, out_dir=out, run_check=False, jobs=1, sensitivities=False,
                             animations=False)
    text = md.read_text()
    assert "Campbell diagram and critical speeds" in text and "unbalance response" in text
    assert "The figures below draw the lowest 6 of the" in text
    rows = re.findall(r"^\| \d+ \| [^|]+ \| ([\d.e+-]+) \| [\d.e+-]+ \| ([\d.e+-]+) \|", text,
                      flags=re.M)
    assert rows, "no critical speed listed"
    for speed, hz in rows:
        assert abs(float(speed) - 2 * math.pi * float(hz)) <= 1e-5 * float(speed)
    sdir = next(p for p in out.iterdir() if p.is_dir() and p.name.endswith("_Omega"))
    for name in ("campbell.png", "unbalance_bode.png", "unbalance_polar.png", "unbalance.csv"):
        assert (sdir / name).stat().st_size > 0


@pytest.mark.filterwarnings("ignore::UserWarning")
def test_beams_are_drawn_as_curves():
    """A 3-D beam is drawn through every node; at the straight reference its Hermite curve
    lies on the beam's axis (distance ≤ 1e-12 of the length); bent along a mode it leaves it."""
    from mbseig.plots.spatial import SEGMENT_POINTS, beam_curve, spatial_layout

    model = load_case(CASES / "cantilever_3d_oblique.toml", n=4)
    beam = spatial_layout(model)["beams"][0]
    q = model.q_init
    curve = beam_curve(model, beam, q)
    nodes = np.array([model.points[p](q) for p in beam["nodes"]])
    assert len(curve) == 4 * SEGMENT_POINTS + 1
    np.testing.assert_allclose(curve[::SEGMENT_POINTS], nodes, rtol=0, atol=1e-15)
    t = (nodes[-1] - nodes[0]) / np.linalg.norm(nodes[-1] - nodes[0])
    off = curve - nodes[0] - np.outer((curve - nodes[0]) @ t, t)
    assert np.max(np.linalg.norm(off, axis=1)) <= 1e-12
    # a small rotation of the tip node's triad about a normal bends the last element
    idx = beam["triads"][-1]
    n = np.cross(t, [0.0, 0.0, 1.0])
    n /= np.linalg.norm(n)
    q2 = q.copy()
    for j in range(3):  # u, v, w of the tip turned by 0.01 rad about n (first order)
        q2[idx[3 * j:3 * j + 3]] += 0.01 * np.cross(n, q[idx[3 * j:3 * j + 3]])
    bent = beam_curve(model, beam, q2)
    off2 = bent - nodes[0] - np.outer((bent - nodes[0]) @ t, t)
    assert np.max(np.linalg.norm(off2, axis=1)) > 1e-4


@pytest.mark.filterwarnings("ignore::UserWarning")
def test_campbell_of_a_spinning_shaft_from_rest():
    """A sweep from Ω = 0 gives the Campbell diagram.  At rest the shaft still has its whirl
    stations (``spin`` given), and its orbits are straight lines: no mode whirls forward or
    backward there. the 1x crossings of the first forward and backward whirl of the
    pinned Rayleigh shaft (cases/spinning_shaft_rayleigh.toml, 8 elements) meet the closed form
    Ω = sqrt(c / (a ∓ 2 ρ I k²)) (from a ω² ∓ b ω − c = 0 with ω = Ω, Friswell et al. 2010
    §5.4) to 1e-4 (the mesh error at 8 elements is < 5e-5, docs/beams3d.md)."""
    from mbseig.studies.campbell import campbell

    spec_path = CASES / "spinning_shaft_rayleigh.toml"
    res = campbell(spec_path, "Omega", np.linspace(0.0, 1000.0, 5), fixed={"n": 8})
    assert res.speeds[0] == 0 and set(res.whirl[0]) <= {"mixed", "none"}
    assert {"forward", "backward"} <= set(res.whirl[-1])
    rho, E, d, di, L = 7810.0, 2.11e11, 0.05, 0.03, 1.0
    A = math.pi * (d**2 - di**2) / 4
    I_area = math.pi * (d**4 - di**4) / 64  # second moment of area
    k = math.pi / L
    a, c, g = rho * A + rho * I_area * k**2, E * I_area * k**4, 2 * rho * I_area * k**2
    want = {"forward": math.sqrt(c / (a - g)), "backward": math.sqrt(c / (a + g))}
    got = {cs["whirl"]: cs["value"] for cs in res.critical_speeds if cs["value"] < 900}
    assert set(got) == {"forward", "backward"}
    for w, v in want.items():
        assert abs(got[w] - v) <= 1e-4 * v
