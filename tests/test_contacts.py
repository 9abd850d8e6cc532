"""Single-sided contacts (DESIGN §8 ``type = "contact"``): normal forces against hand statics, a
contact that would pull released and said so, the modes on each side of lift-off, the lift-off
value as a sweep boundary, the shared example unchanged, and the one-line error of a zero normal.

Hand statics (cases/box_on_contacts_liftoff.toml, source): contacts c1 (−a, −a), c2 (a, −a),
c3 (0, a) under a box of weight m g pushed along x by F at height h: N1 = m g/4 − h F/(2a),
N2 = m g/4 + h F/(2a), N3 = m g/2; c1 lifts off at F = m g a/(2h)."""

import json
import warnings

import numpy as np
import pytest
from conftest import CASES, write_case

import mbseig
from mbseig.cli import main
from mbseig.studies.pipeline import as_spec
from mbseig.studies.steady_sweep import contact_boundaries, lift_off

BOX = CASES / "box_on_contacts_liftoff.toml"
G, M, A, H = 9.81, 20.0, 0.2, 0.8


def _hand(F):
    return {"c1": M * G / 4 - H * F / (2 * A), "c2": M * G / 4 + H * F / (2 * A), "c3": M * G / 2}


@pytest.mark.parametrize("F", [0.0, 10.0, 24.0])
def test_forces_against_hand_statics(F, capsys):
    """All three active below lift-off: forces to 1e-9 relative to m g; 3 DOF; the modes of
    the bushing (x, y, yaw) in closed form, 1e-10 (the case's [expected])."""
    assert main(["modes", str(BOX), "--param", f"F={F}", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert [c["name"] for c in out["contacts"]] == ["c1", "c2", "c3"]
    for c in out["contacts"]:
        assert c["active"] and c["force"] == pytest.approx(_hand(F)[c["name"]], abs=1e-9 * M * G)
    assert out["dof"] == 3 and out["verdict"] == "stable"
    wx, wz = np.sqrt(5e4 / M - (50 / (2 * M)) ** 2), np.sqrt(2e3 / 0.5 - (5 / (2 * 0.5)) ** 2)
    got = sorted(m["eigenvalue"][1] for m in out["modes"])
    np.testing.assert_allclose(got, [wx, wx, wz], rtol=1e-10)


def test_contact_that_would_pull_is_released(capsys):
    """Beyond lift-off (F = 30 N): held active, c1 would pull m g/4 − h F/(2a) = −10.95 N; it is
    released and the result says so (notes, active false); the box gains its tilt: 4 DOF, the
    new tilting mode stable (rotational holding springs).  The other two carry the weight
    (statics with c1 free and the tilt spring: sum of forces m g, 1e-9)."""
    assert main(["modes", str(BOX), "--param", "F=30", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    c = {x["name"]: x for x in out["contacts"]}
    assert not c["c1"]["active"] and c["c1"]["force"] == 0.0
    assert c["c2"]["active"] and c["c3"]["active"]
    assert c["c2"]["force"] + c["c3"]["force"] == pytest.approx(M * G, rel=1e-9)
    notes = out["equilibrium"]["notes"]
    assert any("'c1' released: it would pull (-10.95 N)" in n for n in notes), notes
    assert out["dof"] == 4 and out["verdict"] == "stable"


def test_lift_off_boundary():
    """Lift-off of c1 at F = m g a/(2h) = 24.525 N (hand statics), 1e-9; as a sweep boundary
    of kind "lift-off" over F = 0…40 (3 points)."""
    spec = as_spec(BOX)
    ref = M * G * A / (2 * H)
    assert lift_off(spec, "F", "c1", 0.0, 40.0) == pytest.approx(ref, abs=1e-9)
    (b,) = contact_boundaries(spec, "F", np.linspace(0.0, 40.0, 3))
    assert (b["kind"], b["contact"], b["stability"]) == ("lift-off", "c1", "loss")
    assert b["value"] == pytest.approx(ref, abs=1e-9)
    assert lift_off(spec, "F", "c2", 0.0, 40.0) is None  # c2 only pushes harder


def test_shared_example_runs_unchanged(capsys):
    path = CASES.parent.parent / "shared" / "examples" / "box_on_contacts.toml"
    if not path.exists():
        pytest.skip("the shared examples are not beside this checkout")
    assert main(["modes", str(path), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    forces = {c["name"]: c["force"] for c in out["contacts"]}
    for name, ref in _hand(10.0).items():
        assert forces[name] == pytest.approx(ref, abs=1e-9 * M * G)


def test_no_active_set_holds(tmp_path):
    """Without rotational springs (the example's bushing) a push beyond lift-off tips the box
    over: no active set holds, refused in one line naming the contacts."""
    path = CASES.parent.parent / "shared" / "examples" / "box_on_contacts.toml"
    if not path.exists():
        pytest.skip("the shared examples are not beside this checkout")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with pytest.raises(mbseig.errors.MbseigError) as exc:
            mbseig.equilibrium(mbseig.load_case(str(path), F=40.0))
    assert "\n" not in exc.value.one_line() and "contacts" in exc.value.one_line()


def test_zero_normal_is_one_line(tmp_path, capsys):
    text = BOX.read_text().replace('normal = [0.0, 0.0, 1.0]\nplane_point = [0.0, 0.0, 0.0]\n\n'
                                   '[[joints]]\nname = "c2"',
                                   'normal = [0.0, 0.0, 0.0]\nplane_point = [0.0, 0.0, 0.0]\n\n'
                                   '[[joints]]\nname = "c2"')
    path = write_case(tmp_path, text)
    assert main(["modes", str(path)]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and err.startswith(f"mbseig: {path}: joints[0]"), err
    assert "normal has zero length" in err


def test_contact_in_a_steady_motion_is_refused(tmp_path, capsys):
    text = BOX.read_text().replace("[[bodies]]", '[motion]\nspeed = 1.0\n\n[[bodies]]', 1)
    path = write_case(tmp_path, text)
    assert main(["modes", str(path)]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "point contacts in a steady motion" in err, err
