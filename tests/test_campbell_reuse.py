"""A Campbell sweep from one build (mbseig.studies.campbell.SpeedLine,
mbseig.casefile.speed_update.SpeedUpdate) and the whirl of all modes at once.

Reference: the same sweep with every point built, solved and linearized on its own (the path
taken where the speed enters anything else).  The model of a point is equal element by element
to a full build and its equilibrium is the full build's (the gyroscopic forces vanish at rest),
so every matrix, eigenvalue, whirl and critical speed is the same number: compared exactly."""

from pathlib import Path

import numpy as np
import pytest

import mbseig
from mbseig.casefile import read_case
from mbseig.model.spatial_whirl import lateral_fractions, rotor_geometry, whirl, whirls
from mbseig.studies import campbell as C

CASES = Path(__file__).resolve().parent.parent / "cases"


def _every_point_built(monkeypatch):
    orig = C.SpeedLine.__init__

    def declined(self, *a, **k):
        orig(self, *a, **k)
        self.reason = "declined by the test"

    monkeypatch.setattr(C.SpeedLine, "__init__", declined)


@pytest.mark.parametrize("name", ["ross_example_rotor", "rigid_rotor"])
def test_one_build_gives_the_full_builds_numbers(name, monkeypatch):
    spec = read_case(CASES / f"{name}.toml")
    speeds = np.linspace(0.0, 500.0, 6)
    a = C.campbell(spec, "Omega", speeds)
    assert a.reuse.startswith("one build")
    _every_point_built(monkeypatch)
    b = C.campbell(spec, "Omega", speeds)
    assert b.reuse == "built at every point"
    np.testing.assert_array_equal(a.tracks, b.tracks)
    assert a.whirl == b.whirl and a.kind == b.kind
    assert a.critical_speeds == b.critical_speeds and a.critical_speeds


def test_speed_update_declines_a_speed_elsewhere(tmp_path):
    """A bearing stiffness computed from the speed parameter: the speed enters more than the
    gyroscopic terms, so no point is reused; the reason names where it enters."""
    text = (CASES / "rigid_rotor.toml").read_text()
    assert 'stiffness = ["kx", "ky", "kz",' in text
    path = tmp_path / "rotor.toml"
    path.write_text(text.replace('["kx", "ky",', '["kx", "ky + 0.01 * Omega",', 1))
    line = C.SpeedLine(read_case(path), None, {"Omega": 0.0}, "Omega")
    assert line.reason is not None and line.reason.startswith("Omega enters forces[")


@pytest.mark.parametrize("name,speed", [("overhung_rotor_friswell", 300.0),
                                        ("ross_example_rotor", -200.0),
                                        ("rigid_rotor", 0.0)])
def test_whirls_at_once_equal_one_mode_at_a_time(name, speed):
    a = mbseig.analyze(CASES / f"{name}.toml", params={"Omega": speed})
    md, q0, model = a.modes, a.linear.q0, a.model
    geo = rotor_geometry(model, q0)
    fr = lateral_fractions(model, q0, md.shapes, geometry=geo)
    one = [whirl(model, q0, md.shapes[:, k], md.eigenvalues[k], geometry=geo, fraction=fr[k])
           for k in range(md.shapes.shape[1])]
    assert whirls(model, q0, md.shapes, md.eigenvalues) == one


@pytest.mark.parametrize("example,kzz", [("ex1_friswell_5_9_1_nel6", 1e6),
                                         ("ex3_friswell_5_9_2_nel6", 0.8e6),
                                         ("ex5_friswell_5_9_3_nel6", 0.2e6)])
def test_example_rotor_case_gives_friswell_59x(example, kzz):
    """cases/ross_example_rotor.toml with the larger second disk and the bearings of Friswell's
    ex. 5.9.1–5.9.3 (the rows of mbseig bench --sections lean).  Reference: ROSS 2.3.0's
    eigenvalues of those rotors, same element and mesh (tests/data/ross/friswell_lateral.json),
    at 0 and 4000 rpm; every ROSS eigenvalue has an mbseig one within 1e-8 relative (rounding of
    two formulations of one discrete model: measured ≤ 3e-11; 1e-8 as for the overhung case)."""
    import json

    data = json.loads((Path(__file__).parent / "data" / "ross" / "friswell_lateral.json")
                      .read_text())["examples"][example]
    big = {"m_disk1": 51.5252611115262, "Id1": 0.42358058405433824, "Ip1": 0.8050822048675967}
    for speed, values in data["speeds"].items():
        ross = np.array([complex(a, b) for a, b in values])
        a = mbseig.analyze(CASES / "ross_example_rotor.toml",
                           params={**big, "kzz": kzz, "Omega": float(speed)})
        s = a.modes.eigenvalues
        assert max(np.min(np.abs(s - r)) / abs(r) for r in ross) <= 1e-8
