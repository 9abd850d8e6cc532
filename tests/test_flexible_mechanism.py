"""A mechanism with a flexible link, and FE bodies imported from reduced matrices.

References: the rigid four-bar (cases/four_bar.toml, itself checked against an independent 1-DOF
reduction in tests/test_four_bar.py) is the limit of the flexible coupler as its stiffness grows;
Ritz approximations on nested meshes decrease monotonically to the converged frequencies; a
Craig–Bampton export that keeps every fixed-interface mode is an exact change of coordinates.
"""

import numpy as np
import pytest
from conftest import CASES, write_case

import mbseig
from mbseig.errors import CaseError
from mbseig.model.fe_body import export_fe_body
from mbseig.studies import analyze

FLEX = CASES / "four_bar_flexible.toml"


def _fixed_mesh(tmp_path, source, n, name="fixed.toml"):
    text = source.read_text().replace('elements = "auto"', f"elements = {n}")
    return write_case(tmp_path, text.split("[refinement]")[0] + "[expected]\nsource = \"test\"\n",
                      name)


def test_flexible_coupler_modes_converge_with_mesh(tmp_path):
    w = []
    for n in (2, 4, 8, 16):
        a = analyze(_fixed_mesh(tmp_path, FLEX, n, f"n{n}.toml"))
        w.append(np.sort(a.modes.omega_n)[:3])
    w = np.array(w)
    assert np.all(np.diff(w, axis=0) <= 1e-9 * w[1:])  # monotone from above (nested Ritz spaces)
    change = np.abs(np.diff(w, axis=0)).max(axis=1) / w[-1].max()
    assert change[1] < change[0] / 4 and change[2] < change[1] / 4  # at least h² convergence
    # the refinement the case asks for lands within its accuracy of the finest mesh here
    a = analyze(FLEX)
    np.testing.assert_allclose(np.sort(a.modes.omega_n)[:3], w[-1], rtol=1e-3)
    assert a.refinement.converged


def test_lowest_mode_approaches_rigid_linkage():
    """The mechanism mode tends to the rigid four-bar's as E grows: error ∝ 1/E."""
    w_rigid = analyze(CASES / "four_bar.toml").modes.omega_n[0]
    err = []
    for stiff in (1.0, 10.0, 100.0):
        a = analyze(FLEX, params={"stiff": str(stiff)})
        err.append(abs(a.modes.omega_n[0] / w_rigid - 1))
    assert err[0] < 1e-2
    assert err[1] < err[0] / 8 and err[2] < err[1] / 8
    assert err[2] < 5e-5


FREE_BEAM = """
schema_version = 1
dimension = 2
[[points]]
name = "A"
position = [0.0, 0.0]
[[points]]
name = "B"
position = [1.0, 0.0]
[[beams]]
name = "beam"
points = ["A", "B"]
E = 2.1e11
rho = 7850
section = { shape = "rectangle", b = 0.02, h = 0.01 }
elements = 8
"""

IMPORTED = """
schema_version = 1
dimension = 2
[[points]]
name = "A"
position = [0.0, 0.0]
fixed = true
[[points]]
name = "B"
position = [1.0, 0.0]
[[fe_bodies]]
name = "strip"
mass = {mass}
stiffness = {stiffness}
interface = ["A", "B"]
rotations = ["clamped", "free"]
"""


@pytest.mark.parametrize("fmt, n_modes, rtol", [
    ("npz", None, 1e-9),  # every internal mode kept: exact (rounding only)
    ("mtx", None, 1e-9),
    ("mtx", 6, 2e-3),  # 6 fixed-interface modes: the lowest three within 0.2 %
])
def test_beam_exported_and_imported_gives_same_modes(tmp_path, fmt, n_modes, rtol):
    free = mbseig.load_case(write_case(tmp_path, FREE_BEAM, "free.toml"))
    files = export_fe_body(free, ["A", "B"], tmp_path / f"strip.{fmt}", n_modes=n_modes)
    if fmt == "npz":
        mass, stiffness = '{file = "strip.npz", key = "M"}', '{file = "strip.npz", key = "K"}'
    else:
        mass, stiffness = '{file = "strip_M.mtx"}', '{file = "strip_K.mtx"}'
    assert all((tmp_path / f).exists() for f in files)
    imported = analyze(write_case(tmp_path, IMPORTED.format(mass=mass, stiffness=stiffness),
                                  "imported.toml"))
    direct = analyze(_fixed_mesh(tmp_path, CASES / "cantilever_beam.toml", 8))
    k = 3 if n_modes else direct.modes.omega_n.size
    assert imported.modes.omega_n.size >= k
    np.testing.assert_allclose(imported.modes.omega_n[:k], direct.modes.omega_n[:k], rtol=rtol)
    assert imported.model.flexible["bodies"]["strip"]["interface"] == ["A", "B"]


def test_fe_body_bad_input(tmp_path):
    np.savez(tmp_path / "bad.npz", M=np.eye(4), K=np.eye(5))
    text = IMPORTED.format(mass='{file = "bad.npz", key = "M"}',
                           stiffness='{file = "bad.npz", key = "K"}')
    with pytest.raises(CaseError, match="fe_bodies\\[0\\] 'strip'.*mass is 4×4 but stiffness 5×5"):
        mbseig.load_case(write_case(tmp_path, text))
    text = IMPORTED.format(mass='{file = "nothere.npz", key = "M"}', stiffness="0")
    with pytest.raises(CaseError, match="nothere.npz"):
        mbseig.load_case(write_case(tmp_path, text, "b.toml"))
