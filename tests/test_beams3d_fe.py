"""3-D FE bodies (DESIGN §8): a free 3-D beam exported with 6 rows per interface point gives
the beam's own modes; Craig–Bampton reductions converge to them as modes are added."""

import numpy as np
import pytest
import scipy.linalg as sla
from conftest import write_case

import mbseig
from mbseig.errors import CaseError
from mbseig.model.fe_body import craig_bampton, export_fe_body
from mbseig.model.fe_body3d import node_matrices
from mbseig.studies import analyze

POINTS = """
schema_version = 1
dimension = 3
[[points]]
name = "A"
position = [0.0, 0.0, 0.0]{fixed}
[[points]]
name = "B"
position = [1.0, 0.2, 0.1]
"""
BEAM = """
[[beams]]
name = "beam"
points = ["A", "B"]
E = 2.1e11
G = 8.1e10
rho = 7850
section = {{ shape = "rectangle", b = 0.03, h = 0.02 }}
orientation = [0.0, 0.3, 1.0]
theory = "timoshenko"
elements = 4
ends = {ends}
"""
FE = """
[[fe_bodies]]
name = "bar"
mass = {{file = "bar.npz", key = "M"}}
stiffness = {{file = "bar.npz", key = "K"}}
interface = ["A", "B"]
rotations = {rotations}
"""
CLAMPED = POINTS.format(fixed="\nfixed = true") + BEAM.format(ends='["clamped", "free"]')


def _free(tmp_path):
    return mbseig.load_case(write_case(tmp_path, POINTS.format(fixed="")
                                       + BEAM.format(ends='["free", "free"]'), "free.toml"))


def test_exported_beam_gives_the_beams_modes(tmp_path):
    """Reference: the same oblique Timoshenko beam, clamped–free, as [[beams]] (same mesh);
    every internal mode kept, so the reduction is exact: equal to rounding (1e-9)."""
    export_fe_body(_free(tmp_path), ["A", "B"], tmp_path / "bar.npz")
    fe = POINTS.format(fixed="\nfixed = true") + FE.format(rotations='["clamped", "free"]')
    imported = analyze(write_case(tmp_path, fe, "fe.toml"))
    direct = analyze(write_case(tmp_path, CLAMPED, "beam.toml"))
    w_fe, w_beam = imported.modes.omega_n, direct.modes.omega_n
    assert w_beam.size == 24 and w_fe.size == 24  # 4 elements × 6 dofs, one node clamped
    np.testing.assert_allclose(w_fe, w_beam, rtol=1e-9)
    rec = imported.model.flexible["bodies"]["bar"]
    assert rec["interface_dofs"] == 6 and rec["modal_coordinates"] == 18


def test_craig_bampton_converges_as_modes_are_added(tmp_path):
    """Reference: the clamped–free beam model itself (analyze, constrained coordinates).  The
    reduced models are Ritz subspaces of the node model: the lowest three frequencies
    approach from above, the error falls as modes are added, and all 18 modes are exact."""
    nm = node_matrices(_free(tmp_path))
    boundary = nm.rows("A") + nm.rows("B")
    w_ref = analyze(write_case(tmp_path, CLAMPED, "beam.toml")).modes.omega_n[:3]
    errs = []
    for k in (1, 3, 6, 18):
        Mr, Kr, _ = craig_bampton(nm.M, nm.K, boundary, k)
        keep = np.arange(6, Mr.shape[0])  # A clamped: its 6 interface rows removed
        w = np.sqrt(sla.eigh(Kr[np.ix_(keep, keep)], Mr[np.ix_(keep, keep)], eigvals_only=True)[:3])
        assert np.all(w >= w_ref * (1 - 1e-10))
        errs.append(np.max(w / w_ref - 1))
    assert errs[0] > errs[1] > errs[2] and errs[3] < 1e-10


def test_fe_body_3d_bad_input(tmp_path):
    export_fe_body(_free(tmp_path), ["A", "B"], tmp_path / "bar.npz")
    base = POINTS.format(fixed="\nfixed = true")
    with pytest.raises(CaseError,
                       match=r"fe_bodies\[0\] 'bar'.*neither \"free\", \"clamped\" nor a body"):
        mbseig.load_case(write_case(tmp_path, base + FE.format(rotations='["clamped", "hub"]'),
                                    "a.toml"))
    with pytest.raises(CaseError, match="interface_dofs must be 6"):
        mbseig.load_case(write_case(tmp_path, base + FE.format(rotations='["clamped", "free"]')
                                    + "interface_dofs = 3\n", "b.toml"))
    with pytest.raises(CaseError, match="interface point .C. has no free u_x"):
        node_matrices(_free(tmp_path)).rows("C")


def test_rotation_welded_to_a_fixed_body_is_a_clamp(tmp_path):
    """Reference: the clamped–free beam (same mesh).  A hub welded to the ground carries the
    FE body's rotation at A (rotations = ["hub", "free"]): the same modes to rounding (1e-9)."""
    export_fe_body(_free(tmp_path), ["A", "B"], tmp_path / "bar.npz")
    hub = """
[[bodies]]
name = "hub"
mass = 1.0
com = [0.0, 0.0, 0.0]
inertia = [0.01, 0.01, 0.01]
[[joints]]
name = "hub fix"
type = "weld"
bodies = ["ground", "hub"]
at = [0.0, 0.0, 0.0]
"""
    fe = POINTS.format(fixed="\nfixed = true") + hub + FE.format(rotations='["hub", "free"]')
    welded = analyze(write_case(tmp_path, fe, "weld.toml")).modes.omega_n
    direct = analyze(write_case(tmp_path, CLAMPED, "beam.toml")).modes.omega_n
    assert welded.size == direct.size == 24
    np.testing.assert_allclose(welded, direct, rtol=1e-9)
