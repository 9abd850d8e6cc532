"""The reaction table of ``mbseig check`` / ``mbseig modes --reactions`` (issue: figures and
tables that show numbers, not rounding): per joint the force and moment on a named body in
global and body axes, values within their error bound printed as 0, the bodies' normalization
conditions left out; and ``mbseig check`` on a model without any restoring force says what the
rigid-body probe checked instead of printing ``inf``.

References: the static balance of each free body (Newton's laws: Σ F = 0 and Σ M = 0 with the
joint forces the table reports, action = −reaction), closed forms for the hanging double
pendulum and for a two-point rigid link, and an independent least-squares solve (QR with column
pivoting instead of the SVD) for the multiplier error bound.
"""

import json

import numpy as np
import pytest
import scipy.linalg as sla
from conftest import CASES, write_case

import mbseig
from mbseig.cli import main
from mbseig.statics.reactions import multiplier_error, reaction_forces

G = 9.81


def _rows(name, **params):
    model = mbseig.load_case(CASES / name, **params)
    eq = mbseig.equilibrium(model)
    return model, eq, {r["element"].split("'")[1] if "'" in r["element"] else r["element"]: r
                       for r in reaction_forces(model, eq)}


# ---- spatial joints: RSSR four-bar -------------------------------------------------------
@pytest.fixture(scope="module")
def rssr():
    return _rows("rssr_four_bar.toml")


def test_rssr_joint_rows_and_internal_conditions_apart(rssr):
    _, _, rows = rssr
    joints = {k: r for k, r in rows.items() if r["kind"] == "joint"}
    assert set(joints) == {"crank bearing", "A", "B", "rocker bearing"}
    assert {r["on"] for r in joints.values()} == {"crank", "coupler", "rocker"}
    internal = [r for r in rows.values() if r["kind"] == "internal"]
    assert sorted(r["on"] for r in internal) == ["coupler", "crank", "rocker"]


def test_rssr_free_body_balance(rssr):
    """Σ F = 0 on each body and Σ M = 0 about A on the coupler (Newton's laws), with the joint
    forces as reported (a force "on rocker" at B acts on the coupler reversed), to 1e-9 of the
    weights."""
    model, eq, rows = rssr
    p = model.parameters
    g = np.array([0.0, 0.0, -G])
    F = {k: np.array(r["force"]) for k, r in rows.items() if r["kind"] == "joint"}
    at = {k: np.array(r["at"]) for k, r in rows.items() if r["kind"] == "joint"}
    scale = 1e-9 * G * (p["m1"] + p["m2"] + p["m3"])
    # crank: its bearing (on crank) and A (reported on the coupler: −F on the crank)
    np.testing.assert_allclose(F["crank bearing"] - F["A"] + p["m1"] * g, 0, atol=scale)
    # coupler: A on it, B reported on the rocker
    np.testing.assert_allclose(F["A"] - F["B"] + p["m2"] * g, 0, atol=scale)
    # rocker: B and its bearing, both on it
    np.testing.assert_allclose(F["B"] + F["rocker bearing"] + p["m3"] * g, 0, atol=scale)
    # the coupler's moments about A: spherical joints carry none; weight at its centre of mass
    body = model.bodies["coupler"]
    z = body["frame"](eq.q)  # [r₀; u; v; w]: the centre of mass is r₀ + [u v w](com − origin)
    c = z[:3] + z[3:].reshape(3, 3).T @ (body["com"] - body["origin"])
    M = np.cross(at["B"] - at["A"], -F["B"]) + np.cross(c - at["A"], p["m2"] * g)
    np.testing.assert_allclose(M, 0, atol=scale * 0.5)


def test_rssr_rounding_residue_is_zero_and_bounds_small(rssr):
    """A spherical joint carries no moment and a revolute none about its axis: exact zeros in
    the table (the unzeroed sums were 1e-16 residue), with bounds far below the forces."""
    _, _, rows = rssr
    assert rows["A"]["moment"] == [0.0, 0.0, 0.0] and rows["B"]["moment"] == [0.0, 0.0, 0.0]
    assert rows["crank bearing"]["moment"][2] == 0.0  # axis z, crank's w
    assert rows["crank bearing"]["moment_body"][2] == 0.0
    assert rows["rocker bearing"]["moment_body"][0] == 0.0  # axis x, rocker's u
    for r in rows.values():
        if r["kind"] == "joint":
            assert max(r["error"]["force"]) < 1e-9 * np.linalg.norm(r["force"])
            # body axes: a rotation of the global vector (its length kept to rounding)
            assert np.linalg.norm(r["force_body"]) == pytest.approx(np.linalg.norm(r["force"]),
                                                                    rel=1e-12)


def test_multiplier_bound_covers_an_independent_solve(rssr):
    """λ by QR with column pivoting (gelsy) differs from the statics' SVD solution by less than
    the stated bound, which is not vacuous (< 1e-6 of ‖λ‖)."""
    model, eq, _ = rssr
    est = multiplier_error(model, eq)
    Phi = model.phi_q(eq.q).toarray()
    lam2 = sla.lstsq(Phi.T, model.generalized_force(eq.q), lapack_driver="gelsy")[0]
    assert np.linalg.norm(lam2 - eq.lam) <= est["lambda_bound"]
    assert 0 < est["lambda_bound"] < 1e-6 * np.linalg.norm(eq.lam)


def test_check_table_text_and_json(capsys):
    assert main(["check", str(CASES / "rssr_four_bar.toml"), "--modes", "2", "--periods", "2"]) == 0
    out = capsys.readouterr().out
    table = out[out.index("reactions at equilibrium"):]
    assert "crank.u" not in table and "e-16" not in table and "e-22" not in table
    assert "crank u, v, w:" in table and "global x, y, z:" in table
    assert "not listed: 3 normalization condition(s)" in table
    assert main(["check", str(CASES / "rssr_four_bar.toml"), "--modes", "2", "--periods", "2",
                 "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert [r["element"] for r in d["reactions"]] == [
        "joints[0] 'crank bearing'", "joints[1] 'A'", "joints[2] 'B'", "joints[3] 'rocker bearing'"]
    assert len(d["reactions_internal"]) == 3
    assert d["reaction_error"]["lambda_bound"] > 0
    a = d["reactions"][1]
    assert a["moment"] == [0.0, 0.0, 0.0] and set(a["error"]) >= {"force", "moment", "force_body"}


# ---- shared basic points: spatial double pendulum -----------------------------------------
def test_shared_point_carries_the_lower_weight():
    """A is carried by the upper link and is the lower link's origin: the force on the upper
    link there is the lower link's weight, (0, 0, −m2 g) (closed form, 1e-12)."""
    model, _, rows = _rows("spatial_double_pendulum.toml")
    (r,) = [r for r in rows.values() if r["kind"] == "shared point"]
    assert r["on"] == "upper" and r["point"] == "A" and r["shared_by"] == ["upper", "lower"]
    m2 = model.parameters["m2"]
    np.testing.assert_allclose(r["force"], [0.0, 0.0, -m2 * G], rtol=1e-12, atol=0)
    assert r["force"][:2] == [0.0, 0.0]


# ---- planar bodies: four-bar -------------------------------------------------------------
def test_planar_rigid_length_in_body_axes():
    """A two-point rigid link pushes its end along its own axis only: transverse component
    exactly 0; on its second point the axial component is −(tension) (closed form)."""
    _, _, rows = _rows("four_bar.toml")
    for name in ("crank", "coupler", "rocker"):
        r = rows[name]
        assert r["kind"] == "body" and r["on"] == name
        for axial, transverse in r["forces_body"].values():
            assert transverse == 0.0
            assert abs(axial) == pytest.approx(abs(r["axial_force"]), rel=1e-12)
    assert rows["crank"]["forces_body"]["B"][0] == pytest.approx(-rows["crank"]["axial_force"],
                                                                  rel=1e-12)


# ---- no restoring force at all ------------------------------------------------------------
def test_check_without_restoring_force_says_what_it_checked(tmp_path, capsys):
    text = (CASES / "double_pendulum.toml").read_text().replace('gravity = [0.0, "-g"]\n', "")
    case = write_case(tmp_path, text)
    assert main(["check", str(case)]) == 0
    out = capsys.readouterr().out
    assert "inf" not in out
    assert out.count("ω_ref = 0, no ratio") == 2 and "ω_eff = 0" in out
    assert main(["check", str(case), "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    for m in d["modes"]:
        assert m["probe"]["ratio"] is None and "ω_ref = 0" in m["probe"]["checked"]
    assert all(r["axial_force"] == 0.0 for r in d["reactions"])
