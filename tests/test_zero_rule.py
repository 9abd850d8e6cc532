"""The zero rule and the user's names (DESIGN §6): a value within its error bound of zero reads 0
wherever a person reads it (the JSON keeps the raw value and its bound), and mode shapes are
named by what the case wrote."""

import json
import math
import re

import numpy as np
import pytest
from conftest import CASES

import mbseig
from mbseig.cli import main
from mbseig.display import fmt, fmt_complex, shown, shown_array
from mbseig.model.naming import display_map
from mbseig.studies.design import REL_STEP, eigen_sensitivities

TINY = re.compile(r"[-+]?\d\.?\d*e-(1[3-9]|[2-9]\d|\d{3})\b")  # 1e-13 and below


def test_display_rule():
    assert shown(1e-17, 1e-15) == 0.0 and math.copysign(1, shown(-1e-17, 1e-15)) == 1.0
    assert shown(2e-15, 1e-15) == 2e-15
    assert shown(1e-17, None) == 1e-17  # no bound: nothing is known to be zero
    assert shown(1e-17, float("nan")) == 1e-17
    assert fmt(-7.32e-17, 1e-14) == "0" and fmt(0.25, 1e-14) == "0.25"
    assert fmt(-0.0) == "0"
    assert fmt_complex(1e-16 + 3j, 1e-12, 1e-12, ".3g") == "3i"
    assert fmt_complex(-2 - 3j, 0, 0, ".3g") == "-2 − 3i"
    np.testing.assert_array_equal(shown_array([1e-20, -1.0, 5e-3], [1e-12, 1e-12, 1e-2]),
                                  [0.0, -1.0, 0.0])


@pytest.mark.parametrize("case", ["rigid_rotor", "overhung_rotor_friswell", "spherical_pendulum",
                                  "rolling_disk"])
def test_modes_table_prints_no_number_below_its_bound(case, capsys):
    """Against the raw JSON: a value within its bound (the mode's tolerance) is printed as 0,
    and no printed number of the table is rounding residue (1e-13 and below)."""
    path = str(CASES / f"{case}.toml")
    assert main(["modes", path, "--json"]) == 0
    raw = json.loads(capsys.readouterr().out)
    assert main(["modes", path]) == 0
    text = capsys.readouterr().out
    rows = [ln.split() for ln in text.splitlines() if re.match(r"^\s*\d+\s", ln)]
    assert len(rows) == len(raw["modes"])
    for row, m in zip(rows, raw["modes"], strict=True):
        re_tok = row[1]
        if abs(m["eigenvalue"][0]) <= m["tolerance"]:
            assert re_tok == "0", (row, m["eigenvalue"], m["tolerance"])
        numbers = [t for t in row[1:8] if TINY.fullmatch(t)]
        assert not numbers, row  # (the η column, 8th, is a backward error, not a value)


def test_rotor_names_and_declared_spin(capsys):
    assert main(["modes", str(CASES / "rigid_rotor.toml"), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    names = {n for m in out["modes"] for n, _ in m["dominant"]}
    assert names <= {"rotor x", "rotor y", "rotor z", "rotor θx", "rotor θy", "rotor θz"}
    assert out["modes"][0]["rigid_body"].startswith("rotor: rotation about the line through")


def test_beam_nodes_named_by_station():
    a = mbseig.analyze(CASES / "overhung_rotor_friswell.toml")
    names = {n for d in a.modes.dominant for n, _ in d}
    assert any(n.startswith("shaft.disk") for n in names)  # a station of the case
    assert not any(re.search(r"\.n\d", n) for n in names)


def test_small_rotation_of_a_triad_reads_as_its_angles():
    """δe = δθ × e on each unit vector of a triad reads δθ (½ Σ e × (δθ × e) = δθ for an
    orthonormal triad, exact); a translation of its point reads as itself."""
    model = mbseig.load_case(CASES / "rigid_rotor.toml")
    q = model.q_init
    dmap = display_map(model, q)
    theta, shift = np.array([1e-3, -2e-3, 0.5e-3]), np.array([0.1, 0.2, -0.3])
    dq = np.zeros(model.n)
    names = list(model.coordinate_names)
    for e in "uvw":
        idx = [names.index(f"rotor.{e}.{a}") for a in "xyz"]
        dq[idx] = np.cross(theta, q[idx])
    dq[[names.index(f"rotor.{a}") for a in "xyz"]] = shift
    got = dict(zip(dmap.names, dmap.apply(dq), strict=True))
    np.testing.assert_allclose([got[f"rotor θ{a}"] for a in "xyz"], theta, rtol=1e-14, atol=0)
    np.testing.assert_allclose([got[f"rotor {a}"] for a in "xyz"], shift, rtol=0, atol=0)


def test_sensitivity_within_its_bound_of_the_closed_form():
    """Pendulum s = i √(g/l): ∂s/∂l = −(i/2) √g l^(−3/2) (closed form).  The computed value
    differs by at most its stated bound plus the central difference's truncation
    h²/6 |s'''(l)| (h = REL_STEP·l, s''' = −(15/8) i √g l^(−7/2))."""
    path = CASES / "pendulum.toml"
    vals, bounds = eigen_sensitivities(path, with_bounds=True)
    g, length = 9.81, 1.0
    exact = -0.5j * math.sqrt(g) * length ** -1.5
    h = REL_STEP * length
    trunc = h * h / 6 * 15 / 8 * math.sqrt(g) * length ** -3.5
    assert abs(vals["l"][0] - exact) <= bounds["l"][0] + trunc
    assert bounds["l"][0] < 1e-5 * abs(exact)  # and the bound is informative


def test_rigid_body_sensitivity_reads_zero(capsys):
    assert main(["modes", str(CASES / "rssr_four_bar.toml"), "--sensitivities"]) == 0
    text = capsys.readouterr().out
    line = next(ln for ln in text.splitlines() if ln.startswith("mode 1 ds/dp"))
    assert set(re.findall(r" (\S+?)(?:;|$)", line)) == {"0"}, line
