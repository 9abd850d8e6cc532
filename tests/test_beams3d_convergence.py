"""Spatial beams against their closed forms to 1e-8 relative, with the mesh that reaches it
(issue "3-D flexible bodies and flexible rotors", docs/beams3d.md "Convergence").

Convergence measured here (and by benchmarks/beam3d_large.py on finer meshes):

- bending (cubic Hermite, Euler–Bernoulli and Rayleigh): error ∝ h⁴; 1e-8 needs 96 elements for
  the first two modes of each plane of the oblique cantilever, 128 free-free, and 112 for the
  second whirl pair of the spinning shaft;
- axial and torsion (linear elements, consistent mass): the discrete frequencies are exactly
  ω_h = (c/h) √(6 (1 − cos kh) / (2 + cos kh)), so the error is (kh)²/24 + O(h⁴): 1e-8 directly
  would need 3206 elements on the cantilever, so the test shows the discrete closed form to
  1e-9 and reaches the continuum to 1e-8 by Richardson extrapolation of 48 and 96 elements;
- Timoshenko shafts with shear (Cowper's κ): error ∝ h² (the same element as ROSS's), 1e-8
  directly needs 2448 elements (measured 9.8e-9, about 50 s: benchmarks/beam3d_large.py);
  here Richardson in h² then h⁴ over 24, 48, 96 elements.

The sparse linearization (constraints in the bordered pencil) and the partial path (``n_modes``:
shift-invert, symmetric for the non-spinning bar) keep every
mesh fast; BLAS runs on one thread (a second thread only adds contention at these sizes).
"""

import numpy as np
import pytest
from conftest import CASES, write_case

from mbseig import equilibrium, linearize, load_case, modes
from mbseig.model.spatial_whirl import whirl
from mbseig.numerics import blas_limit

OBLIQUE = (CASES / "cantilever_3d_oblique.toml").read_text()
SHAFT = (CASES / "spinning_shaft_rayleigh.toml").read_text()
# roots of cos x cosh x = -1 (cantilever) and cos x cosh x = 1 (free-free), Blevins, Formulas for
# Natural Frequency and Mode Shape, table 8-1
CANTILEVER_BL = (1.8751040687119611, 4.694091132974175)
FREE_FREE_BL = (4.730040744862704, 7.853204624095838)


def _solve(path, n, n_modes):
    with blas_limit(1):
        m = load_case(path, n=n)
        eq = equilibrium(m)
        md = modes(linearize(m, eq, sparse=True), n_modes=n_modes)
    return m, eq, md


def _nearest(w, ref):
    return w[np.argmin(np.abs(w - ref))]


_BARS = {}


def _bar(tmp_path, free_free, n):
    """(parameters, section properties, sorted ω_n) of the oblique bar at n elements (each mesh
    solved once per session)."""
    if (free_free, n) not in _BARS:
        text = OBLIQUE
        if free_free:
            text = text.replace("fixed = true\n", "fixed = false\n").replace(
                'ends = ["clamped", "free"]', 'ends = ["free", "free"]')
        m, _, md = _solve(write_case(tmp_path, text, f"bar{n}.toml"), n, 22 if free_free else 16)
        props = next(f for f in m.forces if hasattr(f, "props")).props
        _BARS[free_free, n] = m.parameters, props, np.sort(md.omega_n)
    return _BARS[free_free, n]


def _discrete_rod(k, h, c):
    """Linear rod elements with consistent mass on a uniform mesh: the exact frequency of the
    wave sin(kx) (fixed-free and free-free meshes carry it exactly), c the wave speed."""
    return c / h * np.sqrt(6 * (1 - np.cos(k * h)) / (2 + np.cos(k * h)))


@pytest.mark.parametrize("free_free", [False, True])
def test_oblique_bar_bending_both_planes_to_1e8(tmp_path, free_free):
    """The oblique rectangular bar (Euler–Bernoulli), 96 elements clamped–free, 128 free-free:
    the first two bending modes about the section's z and y axes meet (β_n L)² √(E I/(ρ A L⁴))
    (Blevins table 8-1) to 1e-8 relative (reached: cantilever ≤ 4e-9; free-free ≤ 2e-9 (n = 1),
    9.9e-9 (n = 2; 3.1e-8 at 96 elements)).  The first torsion and axial modes equal the
    discrete closed form of linear elements to 1e-9, so their error against the continuum,
    ((2n − 1)π/2 or nπ) √(GJ/ρI_p)/L and the same with E/ρ, is the stated (kh)²/24."""
    n = 128 if free_free else 96
    p, props, w = _bar(tmp_path, free_free, n)
    E, rho, A, L = p["E"], p["rho"], p["A"], p["L"]
    roots = FREE_FREE_BL if free_free else CANTILEVER_BL
    for bl in roots:
        for inertia in (p["Iz"], p["Iy"]):
            ref = bl**2 * np.sqrt(E * inertia / (rho * A * L**4))
            assert abs(_nearest(w, ref) / ref - 1) <= 1e-8
    if free_free:
        assert np.all(w[:6] < 1e-3 * w[6])  # six rigid-body modes
    k = (np.pi if free_free else np.pi / 2) / L
    for c in (np.sqrt(props.G * props.J / (rho * props.polar)), np.sqrt(E / rho)):
        discrete = _discrete_rod(k, L / n, c)
        assert abs(_nearest(w, discrete) / discrete - 1) <= 1e-9
        assert abs(discrete / (k * c) - 1 - (k * L / n) ** 2 / 24) <= 1e-9


def test_cantilever_axial_and_torsion_richardson_to_1e8(tmp_path):
    """Cantilever torsion and axial modes, (π/2L) √(GJ/ρI_p) and (π/2L) √(E/ρ) (closed form):
    48 and 96 elements are off by (kh)²/24 (4.5e-5, 1.1e-5: order 2 measured, ratio 4 ± 1 %),
    their Richardson extrapolation (4 ω₉₆ − ω₄₈)/3 meets the closed form to 1e-8 (reached
    ≤ 1e-9)."""
    got = {}
    for n in (48, 96):
        p, props, w = _bar(tmp_path, False, n)
        k = np.pi / (2 * p["L"])
        refs = (k * np.sqrt(props.G * props.J / (p["rho"] * props.polar)),
                k * np.sqrt(p["E"] / p["rho"]))
        got[n] = [_nearest(w, r) for r in refs]
    for j, ref in enumerate(refs):
        e48, e96 = got[48][j] / ref - 1, got[96][j] / ref - 1
        assert abs(e48 / e96 - 4) <= 0.04
        assert abs((4 * got[96][j] - got[48][j]) / 3 / ref - 1) <= 1e-8


def _shaft_roots(p, n_mode, kappa=None):
    """(ω_B, ω_F) of the pinned-pinned spinning shaft, mode n.  Rayleigh (kappa None):
    a ω² ∓ b ω − c = 0 (case source).  Timoshenko: with r = R sin kx, φ = Φ cos kx e^{iωt}
    (ω > 0 forward), (κGAk² − ρAω²)(EIk² + κGA − ρIω² + ρI_pΩω) − (κGAk)² = 0 (Friswell et al.
    2010 §5.4 in complex form), roots polished by Newton."""
    k = n_mode * np.pi / p["L"]
    A = np.pi * (p["d"] ** 2 - p["di"] ** 2) / 4
    I_area = np.pi * (p["d"] ** 4 - p["di"] ** 4) / 64  # second moment of area
    rho, E, Om = p["rho"], p["E"], p["Omega"]
    if kappa is None:
        a, b, c = rho * A + rho * I_area * k**2, 2 * rho * I_area * Om * k**2, E * I_area * k**4
        root = np.sqrt(b * b + 4 * a * c)
        return (-b + root) / (2 * a), (b + root) / (2 * a)
    s = kappa * p["G"] * A
    poly = np.polymul([-rho * A, 0.0, s * k * k],
                      [-rho * I_area, 2 * rho * I_area * Om, E * I_area * k * k + s])
    poly[-1] -= (s * k) ** 2
    r = np.roots(poly).real
    out = []
    for x in (max(v for v in r if v < 0), min(v for v in r if v > 0)):
        for _ in range(3):
            x -= np.polyval(poly, x) / np.polyval(np.polyder(poly), x)
        out.append(abs(x))
    return tuple(out)


def _shaft(tmp_path, n, timoshenko):
    text = SHAFT.replace("shear_coefficient = 1e12\n", "") if timoshenko else SHAFT
    m, eq, md = _solve(write_case(tmp_path, text, f"shaft{n}.toml"), n, 4)
    order = np.argsort(md.omega_n)[:4]
    labels = [whirl(m, eq.q, md.shapes[:, j], md.eigenvalues[j]) for j in order]
    return m, md.omega_n[order], labels


def test_spinning_rayleigh_shaft_to_1e8(tmp_path):
    """The spinning Rayleigh shaft (cases/spinning_shaft_rayleigh.toml at Ω = 500 rad/s),
    112 elements: backward and forward whirl of n = 1, 2 meet a ω² ∓ b ω − c = 0 to 1e-8
    (reached 2e-10 and 7e-9; order 4: 96 elements give 1.3e-8 for n = 2), with their labels
    from the orbits, and ω_F ω_B = c/a (the product of the roots) to 1e-8."""
    m, w, labels = _shaft(tmp_path, 112, False)
    p = m.parameters
    for n_mode in (1, 2):
        wb, wf = _shaft_roots(p, n_mode)
        got_b, got_f = w[2 * n_mode - 2], w[2 * n_mode - 1]
        assert labels[2 * n_mode - 2:2 * n_mode] == ["backward", "forward"]
        assert abs(got_b / wb - 1) <= 1e-8 and abs(got_f / wf - 1) <= 1e-8
        assert abs(got_b * got_f / (wb * wf) - 1) <= 2e-8


def test_spinning_timoshenko_shaft_richardson_to_1e8(tmp_path):
    """The same shaft as a Timoshenko beam (shear, Cowper's κ for the tube, rotary inertia):
    its characteristic equation per mode (_shaft_roots).  The element converges at order 2 here
    (measured: errors 6.8e-6, 1.7e-6, 4.1e-7 for n = 1 at 24, 48, 96 elements, ratio 4), so 1e-8
    directly would need about 2400 elements; Richardson in h² and then h⁴ over 24, 48, 96
    elements meets the closed form to 1e-8 (reached ≤ 2e-10)."""
    res = {n: _shaft(tmp_path, n, True) for n in (24, 48, 96)}
    m = res[96][0]
    p = m.parameters
    nu = p["E"] / (2 * p["G"]) - 1
    r2 = (p["di"] / p["d"]) ** 2  # Cowper 1966, table 1 (tube)
    kappa = 6 * (1 + nu) * (1 + r2) ** 2 / ((7 + 6 * nu) * (1 + r2) ** 2 + (20 + 12 * nu) * r2)
    for j in range(4):
        wb, wf = _shaft_roots(p, j // 2 + 1, kappa)
        ref = (wb, wf)[j % 2]
        assert res[96][2][j] == ("backward", "forward")[j % 2]
        e = {n: res[n][1][j] for n in res}
        assert abs((e[48] - ref) / (e[96] - ref) - 4) <= 0.05  # order 2
        r1, r2 = (4 * e[48] - e[24]) / 3, (4 * e[96] - e[48]) / 3
        assert abs((16 * r2 - r1) / 15 / ref - 1) <= 1e-8


STODOLA = """schema_version = 1
dimension = 3
[parameters]
Omega = 300.0
L = 0.5
d = 0.03
E = 2.1e11
m = 12.0
Id = 0.06
Ip = 0.11
[[points]]
name = "A"
position = [0.0, 0.0, 0.0]
fixed = true
[[points]]
name = "B"
position = ["L", 0.0, 0.0]
[[beams]]
name = "shaft"
points = ["A", "B"]
E = "E"
nu = 0.3
rho = 1e-6
section = { shape = "circle", d = "d" }
theory = "euler-bernoulli"
elements = 1
ends = ["clamped", "free"]
stations = { tip = "L" }
[[bodies]]
name = "disk"
mass = "m"
com = ["L", 0.0, 0.0]
inertia = ["Ip", "Id", "Id"]
[[joints]]
name = "disk fit"
type = "weld"
bodies = ["shaft.tip", "disk"]
at = ["L", 0.0, 0.0]
[[forces]]
name = "disk spin"
type = "rotor"
body = "disk"
axis = [1.0, 0.0, 0.0]
polar_inertia = "Ip"
speed = "Omega"
"""


def test_overhung_disk_stodola_green(tmp_path):
    """An overhung disk (m, I_d, I_p) on a massless cantilever shaft (ρ = 1e-6 kg/m³: the
    shaft's mass is 1e-9 of the disk's) spinning at Ω: with the tip stiffness K = F⁻¹,
    F = [[L³/3EI, L²/2EI], [L²/2EI, L/EI]], the whirl frequencies solve
    (K₁₁ − mω²)(K₂₂ − I_d ω² + I_p Ω ω) − K₁₂² = 0 (Stodola–Green; Genta, Dynamics of Rotating
    Systems, 2005, §4.4): positive roots forward, negative backward.  One cubic element is
    exact for end loads, so the four whirl frequencies match to 1e-8 (reached 1e-11), with their
    labels; the torsion √(GJ/(L I_p)) and axial √(EA/(L m)) modes too."""
    path = write_case(tmp_path, STODOLA)
    with blas_limit(1):
        m = load_case(path)
        eq = equilibrium(m)
        md = modes(linearize(m, eq))
    p = m.parameters
    EI = p["E"] * np.pi * p["d"] ** 4 / 64
    L = p["L"]
    K = np.linalg.inv([[L**3 / (3 * EI), L**2 / (2 * EI)], [L**2 / (2 * EI), L / EI]])
    poly = np.polymul([-p["m"], 0.0, K[0, 0]], [-p["Id"], p["Ip"] * p["Omega"], K[1, 1]])
    poly[-1] -= K[0, 1] ** 2
    r = np.sort(np.roots(poly).real)
    expected = {abs(x): "forward" if x > 0 else "backward" for x in r}
    G = p["E"] / 2.6
    A = np.pi * p["d"] ** 2 / 4
    extra = [np.sqrt(G * 2 * np.pi * p["d"] ** 4 / 64 / (L * p["Ip"])),
             np.sqrt(p["E"] * A / (L * p["m"]))]
    w = md.omega_n
    for ref, label in expected.items():
        j = int(np.argmin(np.abs(w - ref)))
        assert abs(w[j] / ref - 1) <= 1e-8
        assert whirl(m, eq.q, md.shapes[:, j], md.eigenvalues[j]) == label
    for ref in extra:
        assert abs(_nearest(w, ref) / ref - 1) <= 1e-8



def test_fine_mesh_lowest_modes_are_not_called_rigid_body(tmp_path):
    """The oblique cantilever at 600 elements (3,600 DOF): its lowest four bending modes are
    listed oscillatory, each within its own stated tolerance of (β_n L)² √(E I/(ρ A L⁴))
    (Blevins table 8-1; the h⁴ discretization error at 600 elements is below 1e-11 relative,
    from ≤ 4e-9 at 96 elements).  The zero-pair floor once listed the first two as rigid-body
    at 0 Hz: its radius h = √(ε‖Q‖_F‖x‖²/xᵀMx) bounds ω² within h² (h = 21.7 rad/s here), so s
    may be 0 only when |s| ≤ √safety·h (69 rad/s), not safety·h (217 rad/s) as it was compared
    with |s| = 105 rad/s (mbseig.modal.bounds.zero_pair_floor)."""
    text = OBLIQUE
    m, _, md = _solve(write_case(tmp_path, text, "bar600.toml"), 600, 4)
    p = m.parameters
    E, rho, A, L = p["E"], p["rho"], p["A"], p["L"]
    w = np.abs(md.eigenvalues.imag)
    assert list(md.kind[:4]) == ["oscillatory"] * 4
    for bl in CANTILEVER_BL:
        for inertia in (p["Iz"], p["Iy"]):
            ref = bl**2 * np.sqrt(E * inertia / (rho * A * L**4))
            k = int(np.argmin(np.abs(w - ref)))
            assert abs(w[k] - ref) <= md.tolerance[k]
