"""The local 3-D shaft element: sections, orientation, and the 12×12 matrices against ROSS.

References: ROSS 2.3.0 ``ShaftElement`` matrices dumped by tests/data/ross (ROSS's
scripts/01_shaft_element.py) (ROSS's axis is z; its DOFs per node are x, y, z, α, β, θ, which map
onto this element's (v, w, u, θy, θz, θx): the cyclic relabelling z→x, x→y, y→z keeps spin senses);
Cowper 1966 (shear coefficients); Timoshenko & Goodier 1970 §109 table (rectangle torsion).
"""

import json
import math
from pathlib import Path

import numpy as np
import pytest

from mbseig.errors import CaseError
from mbseig.model.beam3d import (
    BeamProperties3D,
    cowper_shear_coefficient,
    element_matrices,
    rectangle_torsion_constant,
    section_frame,
    section_properties,
)

# copied from ROSS 2.3.0 runs (data/ross/README.md)
ROSS = Path(__file__).resolve().parent / "data" / "ross"
PERM = np.array([1, 2, 0, 4, 5, 3])  # ROSS DOF i is this element's DOF PERM[i]
P12 = np.concatenate([PERM, PERM + 6])


def _ross():
    return json.loads((ROSS / "shaft_element.json").read_text()), np.load(
        ROSS / "shaft_element_matrices.npz")


@pytest.mark.parametrize("tag", ["solid", "tube", "solid_euler_bernoulli", "solid_rayleigh",
                                 "solid_hutchinson", "tube_hutchinson"])
def test_matrices_equal_ross(tag):
    """M, K, G equal ROSS's ShaftElement to rounding (1e-14 of the largest entry)."""
    meta, arrays = _ross()
    m = meta["elements"][tag]
    nu = m["E"] / (2 * m["G_s"]) - 1
    shape = "tube" if m["i_d"] > 0 else "circle"
    sp = section_properties(shape=shape, dims={"d": m["o_d"], "d_inner": m["i_d"]}, nu=nu)
    kappa = m["kappa"] if "hutchinson" in tag else sp["kappa"]  # Hutchinson's κ from ROSS
    theory = "euler-bernoulli" if ("euler" in tag or "rayleigh" in tag) else "timoshenko"
    props = BeamProperties3D(E=m["E"], G=m["G_s"], rho=m["rho"], A=sp["A"], Iy=sp["Iy"],
                             Iz=sp["Iz"], J=sp["J"], kappa_y=kappa, kappa_z=kappa, theory=theory,
                             rotary_inertia=True if "rayleigh" in tag else None)
    em = element_matrices(props, m["L"])
    if m["kappa"] is not None:
        assert sp["kappa"] == pytest.approx(meta["elements"][tag.split("_")[0]]["kappa"],
                                            rel=1e-14)
    assert em.Phi_y == pytest.approx(m["phi"], rel=1e-14, abs=0)
    for key in "MKG":
        ref = arrays[f"{tag}_{key}"]
        ours = getattr(em, key)[np.ix_(P12, P12)]
        assert np.max(np.abs(ours - ref)) <= 1e-14 * np.max(np.abs(ref)), key


def test_matrix_invariants():
    """M, K symmetric, G skew; rigid motions carry no strain energy; the total mass and the
    torsional inertia come out (ρAL, ρI_pL); Kg reproduces the string stiffness N/L on a rigid
    rotation (exact identities)."""
    sp = section_properties(shape="rectangle", dims={"b": 0.03, "h": 0.05}, nu=0.3)
    props = BeamProperties3D(E=2e11, G=2e11 / 2.6, rho=7800, A=sp["A"], Iy=sp["Iy"],
                             Iz=sp["Iz"], J=sp["J"], kappa_y=sp["kappa"], kappa_z=sp["kappa"])
    L = 0.3
    em = element_matrices(props, L)
    assert np.allclose(em.M, em.M.T, rtol=0, atol=1e-15 * abs(em.M).max())
    assert np.allclose(em.K, em.K.T, rtol=0, atol=1e-15 * abs(em.K).max())
    assert np.allclose(em.G, -em.G.T, rtol=0, atol=1e-15 * abs(em.G).max())
    for axis in range(3):  # translations
        t = np.zeros(12)
        t[[axis, axis + 6]] = 1.0
        assert np.linalg.norm(em.K @ t) <= 1e-9 * abs(em.K).max()
        assert t @ em.M @ t == pytest.approx(props.rho * props.A * L, rel=1e-13)
    rz = np.zeros(12)  # rigid rotation about z: v = x θ, θz = θ
    rz[[5, 11]] = 1.0
    rz[7] = L
    assert np.linalg.norm(em.K @ rz) <= 1e-9 * abs(em.K).max() * L
    assert rz @ em.Kg @ rz == pytest.approx(L, rel=1e-13)  # ∫(v′)² dx = L
    tx = np.zeros(12)
    tx[[3, 9]] = 1.0
    assert tx @ em.M @ tx == pytest.approx(props.rho * props.polar * L, rel=1e-13)


def test_cowper_coefficients():
    """Cowper 1966 table 1 at ν = 0.3: circle 0.886, thin tube (r → 1) 0.530, rectangle 0.850."""
    assert cowper_shear_coefficient("circle", {}, 0.3) == pytest.approx(7.8 / 8.8, rel=1e-15)
    assert cowper_shear_coefficient("tube", {"d": 1.0, "d_inner": 1 - 1e-9}, 0.3) == \
        pytest.approx(2 * 1.3 / (4 + 3 * 0.3), rel=1e-8)  # thin-walled limit 2(1+ν)/(4+3ν)
    assert cowper_shear_coefficient("rectangle", {}, 0.3) == pytest.approx(13 / 15.3, rel=1e-15)
    # a tube with r → 0 is the circle
    assert cowper_shear_coefficient("tube", {"d": 1.0, "d_inner": 1e-9}, 0.25) == \
        pytest.approx(cowper_shear_coefficient("circle", {}, 0.25), rel=1e-15)


@pytest.mark.parametrize("ratio, beta", [(1.0, 0.141), (1.5, 0.196), (2.0, 0.229),
                                         (3.0, 0.263), (5.0, 0.291), (10.0, 0.312)])
def test_rectangle_torsion_constant(ratio, beta):
    """J = β a t³, β from Timoshenko & Goodier §109 (3 decimals: ±6e-4 absolute); Roark's
    approximation a t³[1/3 − 0.21 (t/a)(1 − t⁴/(12a⁴))] within 0.5 %; symmetric in b, h."""
    a, t = ratio * 0.01, 0.01
    J = rectangle_torsion_constant(a, t)
    assert J / (a * t**3) == pytest.approx(beta, abs=6e-4)
    roark = a * t**3 * (1 / 3 - 0.21 * (t / a) * (1 - t**4 / (12 * a**4)))
    assert J == pytest.approx(roark, rel=5e-3)
    assert rectangle_torsion_constant(t, a) == J


def test_rectangle_axes():
    """b along y, h along z: Iy = b h³/12, Iz = h b³/12 (definition of §8)."""
    sp = section_properties(shape="rectangle", dims={"b": 0.02, "h": 0.06}, nu=0.3)
    assert sp["Iy"] == pytest.approx(0.02 * 0.06**3 / 12, rel=1e-15)
    assert sp["Iz"] == pytest.approx(0.06 * 0.02**3 / 12, rel=1e-15)


def test_section_frame_orientation():
    R = section_frame([0, 0, 0], [1, 1, 0], [0, 1, 1])
    assert np.allclose(R.T @ R, np.eye(3), atol=1e-15)
    assert np.linalg.det(R) == pytest.approx(1.0)
    assert np.allclose(R[:, 0], np.array([1, 1, 0]) / math.sqrt(2))
    y = np.array([0, 1, 1.0]) - 0.5 * np.array([1, 1, 0.0])  # projected orientation
    assert np.allclose(R[:, 1], y / np.linalg.norm(y))
    with pytest.raises(CaseError, match="along the beam axis"):
        section_frame([0, 0, 0], [1, 1, 0], [2, 2, 0], element="beam 'b'")


@pytest.mark.parametrize("shape, dims, msg", [
    ("circle", {"d": 0.0}, "must be positive"),
    ("tube", {"d": 0.02, "d_inner": 0.03}, "must be less than"),
    ("rectangle", {"b": 0.01, "h": -1.0}, "must be positive"),
    ("hexagon", {"d": 1.0}, "shape must be one of")])
def test_bad_sections(shape, dims, msg):
    with pytest.raises(CaseError, match=msg) as info:
        section_properties(shape=shape, dims=dims, nu=0.3, element="beam 'shaft'")
    assert info.value.element == "beam 'shaft'"
