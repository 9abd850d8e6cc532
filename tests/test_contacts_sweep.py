"""`mbseig sweep` on a static case with single-sided contacts reports where a contact lifts
off as a boundary of kind "lift-off" (DESIGN §8, "Steady motions, rolling and contact").

Reference: hand statics of cases/box_on_contacts_liftoff.toml (stated in the case): the normal
force of contact c1 is N1 = m g/4 − h F/(2a), zero at F* = m g a/(2h) = 24.525 N for m = 20 kg,
g = 9.81 m/s², a = 0.2 m, h = 0.8 m. Tolerance 1e-9 relative: the lift-off is located by a
bracketing root search to xtol 1e-12 on a force that is linear in F.
"""

import json

import pytest
from conftest import CASES

from mbseig.cli import main


def test_sweep_reports_lift_off(tmp_path, capsys):
    code = main(["sweep", str(CASES / "box_on_contacts_liftoff.toml"), "--param", "F=0:40:5",
                 "--json", "--no-progress", "--jobs", "1", "--out", str(tmp_path)])
    assert code == 0
    out = json.loads(capsys.readouterr().out)
    lift = [b for b in out["boundaries"] if b["kind"] == "lift-off"]
    assert len(lift) == 1
    assert lift[0]["contact"] == "c1" and lift[0]["stability"] == "loss"
    assert lift[0]["value"] == pytest.approx(20.0 * 9.81 * 0.2 / (2 * 0.8), rel=1e-9)
