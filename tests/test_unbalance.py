"""``mbseig unbalance``: the synchronous response to an unbalance against the Jeffcott rotor's
closed form, its outputs (table, JSON, CSV, figures) and its one-line refusals."""

import json
import math

import numpy as np
import pytest

from conftest import CASES, write_case
from mbseig.cli import main

# A Jeffcott rotor built from 3-D parts: a disk (m = 10 kg) welded to the middle station of a
# short, stiff, almost massless Timoshenko shaft (0.5 m, d = 50 mm, rho = 1 kg/m^3: 9.8e-4 kg),
# on one bushing at that station (lateral k = 1e6 N/m, c = 200 N s/m).  The shaft and the disk
# are symmetric about the bearing, so translation decouples from tilt, and the shaft's lowest
# bending mode (free-free halves) lies far above the speeds swept: the centre moves as the
# Jeffcott rotor of mass m + rho A L.
JEFFCOTT_3D = """schema_version = 1
title = "Jeffcott rotor on a short stiff shaft"
dimension = 3
[parameters]
Omega = 100.0   # rad/s
m = 10.0
k = 1e6
c = 200.0
[[points]]
name = "left"
position = [-0.25, 0.0, 0.0]
[[points]]
name = "right"
position = [0.25, 0.0, 0.0]
[[beams]]
name = "shaft"
points = ["left", "right"]
E = 2.1e11
nu = 0.3
rho = 1.0
section = { shape = "circle", d = 0.05 }
theory = "timoshenko"
elements = 2
ends = ["free", "free"]
stations = { mid = 0.25 }
spin = "Omega"
[[bodies]]
name = "disk"
mass = "m"
com = [0.0, 0.0, 0.0]
inertia = [0.2, 0.1, 0.1]
[[joints]]
name = "fit"
type = "weld"
bodies = ["shaft.mid", "disk"]
at = [0.0, 0.0, 0.0]
[[forces]]
name = "disk spin"
type = "rotor"
body = "disk"
axis = [1.0, 0.0, 0.0]
polar_inertia = 0.2
speed = "Omega"
[[forces]]
name = "bearing"
type = "bushing"
bodies = ["ground", "shaft.mid"]
stiffness = ["k", "k", "k", 1e4, 1e4, 1e4]
damping = [0.0, "c", "c", 0.0, 0.0, 0.0]
[[outputs]]
name = "z_mid"
quantity = "position"
point = "shaft.mid"
direction = [0.0, 0.0, 1.0]
"""

M_TOTAL = 10.0 + 1.0 * math.pi * 0.05**2 / 4 * 0.5  # disk + shaft (rho A L)


def closed_form(w, me, angle):
    """Jeffcott rotor: X1 = m e Ω² e^{iφ} / (k − m Ω² + i c Ω) (Genta, Dynamics of Rotating
    Systems, 2005, §3.3)."""
    return me * w**2 * np.exp(1j * angle) / (1e6 - M_TOTAL * w**2 + 1j * 200.0 * w)


def run_json(capsys, argv):
    assert main(argv) == 0
    return json.loads(capsys.readouterr().out)


@pytest.mark.filterwarnings("ignore::UserWarning")
def test_unbalance_command_matches_jeffcott_closed_form(tmp_path, capsys):
    """Amplitude and phase at the disk and at the bearing station against the closed form at
    five speeds (0 to 600 rad/s) through the critical speed sqrt(k/m) ≈ 316 rad/s (asserted 1e-8
    relative on the complex amplitude: measured ≤ 1e-9, the shaft's flexibility and rounding);
    the second lateral component is X2 = −i X1 (a forward circle); the unbalance angle rotates
    the response by itself; the named output z = −x1 (e1 = −z) follows."""
    path = write_case(tmp_path, JEFFCOTT_3D)
    me, angle = 2e-3, 30.0
    out = run_json(capsys, ["unbalance", str(path), "--param", "Omega=0:500:2", "--param",
                            "c=200", "--at", "shaft.mid", "--me", str(me), "--angle", "30",
                            "--json"])
    assert out["speed"] == [0.0, 500.0]
    out = run_json(capsys, ["unbalance", str(path), "--param", "Omega=0:600:5", "--at", "disk",
                            "--me", str(me), "--angle", str(angle), "--json"])
    assert out["units"]["phase"] == "deg" and out["unbalance"]["m_e"] == me
    speeds = np.array(out["speed"])
    np.testing.assert_allclose(speeds, np.linspace(0, 600, 5), rtol=0, atol=0)
    X = closed_form(speeds, me, math.radians(angle))
    e1 = np.array(out["directions"]["e1"])
    rows = {r["station"]: r for r in out["stations"]}
    assert {"disk: centre of mass", "shaft.mid", "left", "right"} <= set(rows)
    for name in ("disk: centre of mass", "shaft.mid"):
        r = rows[name]
        got1 = np.array(r["amplitude_1"]) * np.exp(1j * np.radians(r["phase_1"]))
        got2 = np.array(r["amplitude_2"]) * np.exp(1j * np.radians(r["phase_2"]))
        np.testing.assert_allclose(got1, X, rtol=1e-8, atol=1e-8 * np.abs(X).max())
        np.testing.assert_allclose(got2, -1j * X, rtol=1e-8, atol=1e-8 * np.abs(X).max())
        np.testing.assert_allclose(r["major"], np.abs(X), rtol=1e-8, atol=1e-20)
    y = out["outputs"][0]
    assert y["output"] == "z_mid" and y["unit"] == "m"
    got = np.array(y["amplitude"]) * np.exp(1j * np.radians(y["phase"]))
    np.testing.assert_allclose(got, e1[2] * X, rtol=1e-8, atol=1e-8 * np.abs(X).max())


@pytest.mark.filterwarnings("ignore::UserWarning")
def test_unbalance_table_and_files(tmp_path, capsys):
    """The text table lists every speed at every station and output; --out writes the CSV,
    the JSON and the Bode and polar figures."""
    path = write_case(tmp_path, JEFFCOTT_3D)
    out = tmp_path / "out"
    assert main(["unbalance", str(path), "--param", "Omega=100:500:3", "--at", "shaft.mid",
                 "--me", "1e-3", "--out", str(out)]) == 0
    text = capsys.readouterr().out
    lines = [ln for ln in text.splitlines() if ln.strip().startswith(("100 ", "300 ", "500 "))]
    assert len(lines) == 3 * 6  # 3 speeds × (disk: CoM, disk: weld, left, mid, right, z_mid)
    assert "phase X1 [deg]" in text and "Omega [rad/s]" in text
    X = closed_form(np.array([300.0]), 1e-3, 0.0)[0]
    mid = next(ln for ln in lines if "shaft.mid" in ln and ln.strip().startswith("300 "))
    assert abs(float(mid.split()[2]) - abs(X)) <= 1e-5 * abs(X)  # printed to 6 digits
    for name in ("unbalance.csv", "unbalance.json", "unbalance_bode.png", "unbalance_polar.png"):
        assert (out / name).stat().st_size > 0
    assert (out / "unbalance.csv").read_text().count("\n") == 1 + 3 * 6


@pytest.mark.parametrize("argv, words", [
    (["--at", "shaft.nowhere", "--me", "1e-3"], ["--at", "shaft.nowhere"]),
    (["--at", "disk", "--me", "0"], ["--me"]),
    (["--at", "disk", "--me", "1e-3", "--station", "nowhere"], ["--station", "nowhere"]),
])
def test_unbalance_bad_input_one_line(tmp_path, capsys, argv, words):
    path = write_case(tmp_path, JEFFCOTT_3D)
    code = main(["unbalance", str(path), "--param", "Omega=0:100:2"] + argv)
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1 and all(w in err for w in words)


def test_unbalance_refuses_a_case_without_rotor(tmp_path, capsys):
    text = JEFFCOTT_3D.replace('spin = "Omega"\n', "").split("[[forces]]\nname = \"disk spin\"")[0]
    text += JEFFCOTT_3D[JEFFCOTT_3D.index('[[forces]]\nname = "bearing"'):]
    path = write_case(tmp_path, text)
    code = main(["unbalance", str(path), "--param", "Omega=0:100:2", "--at", "disk", "--me",
                 "1e-3"])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1
    assert str(path) in err and "unbalance" in err and "no spinning rotor" in err


@pytest.mark.filterwarnings("ignore::UserWarning")
def test_a_spinning_beam_alone_is_a_rotor_at_rest_too(tmp_path, capsys):
    """Without the disk's rotor element the shaft's spin makes the case a rotor: at Ω = 0 the
    response is 0 (no unbalance force), above it the Jeffcott closed form (1e-8 relative; the
    disk's gyroscopic moment does not enter the translation)."""
    text = JEFFCOTT_3D.replace(JEFFCOTT_3D[JEFFCOTT_3D.index('[[forces]]\nname = "disk spin"'):
                                           JEFFCOTT_3D.index('[[forces]]\nname = "bearing"')], "")
    path = write_case(tmp_path, text)
    out = run_json(capsys, ["unbalance", str(path), "--param", "Omega=0:400:3", "--at",
                            "shaft.mid", "--me", "1e-3", "--json"])
    assert out["speed"] == [0.0, 200.0, 400.0]
    r = next(r for r in out["stations"] if r["station"] == "shaft.mid")
    X = closed_form(np.array(out["speed"]), 1e-3, 0.0)
    got = np.array(r["amplitude_1"]) * np.exp(1j * np.radians(r["phase_1"]))
    assert got[0] == 0
    np.testing.assert_allclose(got[1:], X[1:], rtol=1e-8)


def test_report_rotor_section_from_the_command_line(tmp_path, capsys):
    """``mbseig report --speeds NAME=START:STOP:COUNT --unbalance AT:M_E`` adds the rotor section
    (Campbell diagram, critical speeds, unbalance response at the stated m·e) without a
    [[report.studies]] entry; a malformed option is one line naming it, exit 2."""
    out = tmp_path / "rep"
    rotor = str(CASES / "rigid_rotor.toml")
    assert main(["report", rotor, "--speeds", "Omega=0:800:5", "--unbalance",
                 "rotor:2e-4", "--no-check", "--no-sensitivities", "--no-studies",
                 "--no-animations", "--out", str(out)]) == 0
    md = (out / "report.md").read_text()
    assert "Campbell diagram and critical speeds" in md
    assert "m·e = 0.0002 kg m" in md
    assert (out / "rigid_rotor_rotor_Omega" / "unbalance.csv").exists()
    # Ω = 0 (no force: exactly 0) and 400 rad/s = √(2kz/m) (undamped critical speed, driven: a
    # resonance, blank and flagged) are on the grid; tests/test_resonance.py checks the values
    assert "Resonance at Omega = 400 rad/s" in md
    rows = (out / "rigid_rotor_rotor_Omega" / "unbalance.csv").read_text().splitlines()
    assert all(r.endswith(",true") == r.startswith("400.0,") for r in rows[1:])
    assert all(r.split(",")[3] == "0.0" for r in rows[1:] if r.startswith("0.0,"))
    capsys.readouterr()
    for bad, option in ((["--speeds", "Omega=0:800"], "--speeds"),
                        (["--unbalance", "rotor:-1"], "--unbalance")):
        assert main(["report", rotor, "--no-check", "--out", str(out), *bad]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and option in err[0] and "rigid_rotor.toml" in err[0]


def _csv_rows(response, path):
    import csv

    response.write_csv(path)
    with open(path) as fh:
        return list(csv.DictReader(fh))


def _rotor_study_case(tmp_path, unbalance, sweep="Omega"):
    text = (CASES / "rigid_rotor.toml").read_text() + (
        f'\n[[report.studies]]\ntitle = "speed"\nsweep = "{sweep}"\n'
        f'range = [100.0, 700.0]\ncount = 4\n'
        + (f"unbalance = {unbalance}\n" if unbalance else ""))
    return str(write_case(tmp_path, text.replace("cy = 0.0 ", "cy = 400.0 ").replace(
        "cz = 0.0", "cz = 600.0"), name="rotor.toml"))


def test_report_study_names_its_unbalance(tmp_path, capsys):
    """A ``[[report.studies]]`` sweep over a rotor's speed takes its own ``unbalance = {at, me}``.
    Reference: the synchronous response is linear in m·e, so the report's amplitudes at m·e =
    2e-4 kg m are 2e-4 times those of the study's default 1 kg m at the same points, computed
    without a report (mbseig.studies.campbell.rotor_study; rtol 1e-12: rounding of one scaling).
    A bad entry is one line naming the entry, exit 2."""
    import csv

    from mbseig.studies.campbell import rotor_study

    out = tmp_path / "own"
    case = _rotor_study_case(tmp_path, '{ at = "rotor", me = 2e-4 }')
    assert main(["report", case, "--no-check", "--no-sensitivities", "--no-animations", "--out",
                 str(out)]) == 0
    assert "m·e = 0.0002 kg m at rotor" in (out / "report.md").read_text()
    [path] = out.glob("*/unbalance.csv")
    with open(path) as fh:
        rows = list(csv.DictReader(fh))
    own = np.array([[float(v) for k, v in r.items() if k.startswith("amplitude")] for r in rows])
    rs = rotor_study(case, "Omega", sorted({float(r["Omega"]) for r in rows}))
    assert rs.default_unbalance and rs.me == 1.0
    default = np.array([[float(v) for k, v in r.items() if k.startswith("amplitude")]
                        for r in _csv_rows(rs.unbalance, tmp_path / "default.csv")])
    assert own.shape == default.shape and own.max() > 0
    np.testing.assert_allclose(own, 2e-4 * default, rtol=1e-12, atol=0)
    capsys.readouterr()
    for ub, sweep, words in (('{ at = "nowhere", me = 1e-4 }', "Omega", "unknown point"),
                             ('{ at = "rotor", me = -1.0 }', "Omega", "me must be"),
                             ('{ at = "rotor", m = 1.0 }', "Omega", "unknown field"),
                             ('{ at = "rotor", me = 1e-4 }', "ky", "rotor's speed")):
        assert main(["report", _rotor_study_case(tmp_path, ub, sweep), "--no-check",
                     "--no-sensitivities", "--out", str(tmp_path / "bad")]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and "report.studies[0].unbalance" in err[0] and words in err[0], err


def test_unbalance_table_names_stations_as_the_case_does(capsys):
    """The unbalance table of a rotor on a beam names every station as the case does (a point,
    ``BEAM.STATION``, an element's own name) or by its arc length, never by a node index
    (``shaft.n1``) or an element's place in the case with its name (``joints[0] 'disk fit'``),
    and prints no rounding sign on a phase (−0.000, −180.000: the same angles as 0 and 180)."""
    import re

    assert main(["unbalance", str(CASES / "overhung_rotor_friswell.toml"), "--param",
                 "Omega=100:300:2", "--at", "shaft.disk", "--me", "1e-4"]) == 0
    table = capsys.readouterr().out
    assert re.search(r"\.n\d+\b", table) is None and "[0] '" not in table
    assert "shaft at s = 0.25 m" in table and "disk: disk fit" in table
    assert "-0.000" not in table and "-180.000" not in table
