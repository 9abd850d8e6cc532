"""Spatial beams and flexible rotors through the pipeline (DESIGN §8, "3-D flexible bodies and
flexible rotors"): the bundled 3-D beam cases against their closed forms, whirl labels of a
spinning shaft, the Euler load, Campbell critical speeds, ROSS's Friswell rotors at the same mesh,
bearing tables and the one-line errors.  Each reference names its source and tolerance.
"""

import importlib.util
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from conftest import CASES, ROOT, write_case

from mbseig import equilibrium, linearize, load_case, modes
from mbseig.casefile import read_case
from mbseig.errors import CaseError
from mbseig.model.spatial_forces import QuadraticSpringDamper
from mbseig.model.spatial_whirl import whirl
from mbseig.studies import analyze
from mbseig.studies.campbell import campbell

SHAFT = CASES / "spinning_shaft_rayleigh.toml"
# the format examples of DESIGN §8 (../shared/examples beside the checkout)
EXAMPLE = Path(__file__).resolve().parents[2] / "shared" / "examples" / "overhung_rotor.toml"
ROSS = Path(__file__).resolve().parent / "data" / "ross"


def _rayleigh(p, n_mode):
    """Forward and backward whirl of the pinned-pinned Rayleigh shaft (closed form in the case's
    source: a w² ∓ b w − c = 0)."""
    k = n_mode * np.pi / p["L"]
    A = np.pi * (p["d"] ** 2 - p["di"] ** 2) / 4
    I_area = np.pi * (p["d"] ** 4 - p["di"] ** 4) / 64  # second moment of area
    a, b, c = (p["rho"] * A + p["rho"] * I_area * k**2, 2 * p["rho"] * I_area * p["Omega"] * k**2,
               p["E"] * I_area * k**4)
    root = np.sqrt(b * b + 4 * a * c)
    return (b + root) / (2 * a), (-b + root) / (2 * a)


def _whirl_modes(n, count=6):
    """(omega, whirl) of the lowest ``count`` listed modes of the spinning shaft at n elements."""
    a = analyze(SHAFT, params={"n": n})
    w = [whirl(a.model, a.eq.q, a.modes.shapes[:, k], a.modes.eigenvalues[k]) for k in range(count)]
    return a.model.parameters, a.modes.eigenvalues.imag[:count], w


def test_spinning_shaft_whirl_labels_and_richardson():
    """The lowest modes at 8 and 16 elements: backward below forward for n = 1, 2 with labels
    'backward' / 'forward' from the orbits of every node (the forward branch turns with the
    spin: it is the higher one, closed form); the torsion mode (about 4.9e3 rad/s) has whirl
    'none'.  16 elements alone: within 2e-5 (order-4 element).  Richardson extrapolation of
    (8, 16) meets the closed form to 1e-8 relative for n = 1 (reached 3.6e-9) and 5e-7 for
    n = 2 (reached 2.3e-7; with (12, 24) elements 2e-8, not run here for time)."""
    p, w16, lab16 = _whirl_modes(16)
    _, w8, lab8 = _whirl_modes(8)
    ref = []
    for n_mode, tol in ((1, 1e-8), (2, 5e-7)):
        wf, wb = _rayleigh(p, n_mode)
        ref += [(wb, "backward", tol), (wf, "forward", tol)]
    for k, (w_ref, label, tol) in enumerate(ref):
        assert lab16[k] == label and lab8[k] == label
        assert abs(w16[k] - w_ref) <= 2e-5 * w_ref
        extrapolated = (16 * w16[k] - w8[k]) / 15
        assert abs(extrapolated - w_ref) <= tol * w_ref
    torsion = [lab for w, lab in zip(w16, lab16, strict=True) if 4000 < w < 6000]
    assert torsion == ["none"]


def test_column_buckles_at_the_euler_load():
    """Pinned column: stable below the Euler load of the extensible column P_E/λ (λ = 1 − P/EA,
    case source), divergence (a real positive eigenvalue) above it: ±0.1 % around P_E (the
    8-element mesh's buckling load is within 1e-5 of P_E, the closed form)."""
    below = analyze(CASES / "column_buckling_3d.toml", params={"Pfrac": 0.999, "n": 8})
    above = analyze(CASES / "column_buckling_3d.toml", params={"Pfrac": 1.001, "n": 8})
    assert below.modes.verdict != "unstable"
    assert above.modes.verdict == "unstable"
    s = above.modes.eigenvalues
    assert np.any((s.real > 0) & (np.abs(s.imag) <= 1e-9 * np.abs(s).max()))


def test_campbell_critical_speeds_closed_form():
    """`campbell` over Omega on the spinning shaft (8 elements): the synchronous crossings of
    the first pair are the closed-form critical speeds of the Rayleigh shaft, w = Omega in
    a w² ∓ b w − c = 0: Omega_F² = c/(rho A − rho I k²), Omega_B² = c/(rho A + 3 rho I k²)
    (8-element discretization error below 2e-5, asserted 5e-5); log decrements of the undamped
    shaft are rounding noise (below 1e-9)."""
    spec = read_case(SHAFT)
    res = campbell(spec, "Omega", [600.0, 900.0], fixed={"n": 8})
    p = spec.build(n=8).parameters
    k = np.pi / p["L"]
    A = np.pi * (p["d"] ** 2 - p["di"] ** 2) / 4
    I_area = np.pi * (p["d"] ** 4 - p["di"] ** 4) / 64  # second moment of area
    c = p["E"] * I_area * k**4
    ref = {"forward": np.sqrt(c / (p["rho"] * A - p["rho"] * I_area * k**2)),
           "backward": np.sqrt(c / (p["rho"] * A + 3 * p["rho"] * I_area * k**2))}
    got = {cs["whirl"]: cs["value"] for cs in res.critical_speeds}
    assert set(got) == {"forward", "backward"}
    for lab, v in ref.items():
        assert abs(got[lab] - v) <= 5e-5 * v
    ld = res.log_decrement[np.isfinite(res.log_decrement)]
    assert np.all(np.abs(ld) < 1e-9)
    assert json.dumps(res.to_json())  # the sweep's JSON carries every track's log decrement


def _ross_module():
    spec = importlib.util.spec_from_file_location("ross_friswell",
                                                  ROOT / "benchmarks" / "ross_friswell.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


@pytest.mark.parametrize("example", ["ex1_friswell_5_9_1_nel6", "ex3_friswell_5_9_2_nel6",
                                     "ex5_friswell_5_9_3_nel6"])
def test_friswell_rotors_match_ross(example):
    """Friswell et al. 2010 ex. 5.9.1 (isotropic bearings), 5.9.2 and 5.9.3 (anisotropic) as
    ROSS 2.3.0 builds them, 6 Timoshenko elements, at 0 and 418.879 rad/s: every ROSS eigenvalue
    (|s| > 0.1: lateral modes and the torsion mode; tests/data/ross) has an mbseig eigenvalue
    within 1e-6 relative (reached: ≤ 1e-10; the same element, so only rounding differs)."""
    mod = _ross_module()
    data = json.loads((ROSS / "friswell_lateral.json").read_text())["examples"][example]
    for speed, s in data["speeds"].items():
        ross = np.array([complex(a, b) for a, b in s])
        ours, _, _ = mod.mbseig_eigenvalues(data["model"], float(speed))
        assert mod.compare(ross, ours) <= 1e-6


@pytest.mark.skipif(not Path(EXAMPLE).exists(),
                    reason="the format examples are not beside this checkout")
def test_overhung_example_runs_with_whirl():
    """The shared format example runs unchanged: exit 0, every mode with a whirl label."""
    out = subprocess.run([sys.executable, "-m", "mbseig", "modes", str(EXAMPLE), "--json"],
                         capture_output=True, text=True, timeout=120, check=False)
    assert out.returncode == 0, out.stderr
    res = json.loads(out.stdout)
    assert res["modes"] and all(m["whirl"] in ("forward", "backward", "mixed", "none")
                                for m in res["modes"])
    assert {"forward", "backward"} <= {m["whirl"] for m in res["modes"]}


@pytest.mark.skipif(not Path(EXAMPLE).exists(),
                    reason="the format examples are not beside this checkout")
def test_bearing_table_interpolates_linearly():
    """Bearing 2 of the example at Omega = 250, halfway between the table's 0 and 500: the
    mean of the two entries (linear interpolation, exact)."""
    m = load_case(EXAMPLE, Omega=250.0)
    b2 = next(f for f in m.forces if isinstance(f, QuadraticSpringDamper) and "bearing 2" in f.name)
    expected = np.diag([0.0, 4.5e7, 4.25e7, 0.0, 0.0, 0.0])
    np.testing.assert_array_equal(b2.stiffness, expected)


BASE = """schema_version = 1
dimension = 3
[parameters]
Omega = 100.0
[[points]]
name = "A"
position = [0.0, 0.0, 0.0]
fixed = true
[[points]]
name = "B"
position = [1.0, 0.0, 0.0]
[[beams]]
name = "bar"
points = ["A", "B"]
E = 2.1e11
nu = 0.3
rho = 7800.0
elements = 4
ends = ["clamped", "free"]
{beam}
[[forces]]
name = "bearing"
type = "bushing"
bodies = ["ground", "bar.s"]
stiffness = {{ parameter = "Omega", at = [0.0, 50.0], \
values = [[1, 1, 1, 0, 0, 0], [2, 2, 2, 0, 0, 0]] }}
"""


@pytest.mark.parametrize("beam, message", [
    ('section = { shape = "rectangle", b = 0.0, h = 0.02 }\nstations = { s = 0.5 }',
     "beams[0] 'bar'.section: b must be positive, got 0"),
    (('section = { shape = "rectangle", b = 0.01, h = 0.02 }\norientation = [2.0, 0.0, 0.0]\n'
      'stations = { s = 0.5 }'), "is along the beam axis"),
    ('section = { shape = "circle", d = 0.02 }\nstations = { s = 1.5 }',
     "beams[0] 'bar'.stations: station 's' at s = 1.5 is outside the beam [0, 1]"),
    ('section = { shape = "circle", d = 0.02 }\nstations = { s = 0.5 }',
     "forces[0] 'bearing': stiffness: Omega = 100 is outside the table [0, 50]"),
    ('A = -1.0\nIy = 1e-8\nIz = 1e-8\nJ = 2e-8\nstations = { s = 0.5 }',
     "A must be positive, got -1"),
])
def test_bad_input_one_line(tmp_path, beam, message):
    """Exit 2 and one line `mbseig: FILE: ELEMENT: problem` (DESIGN §8)."""
    path = write_case(tmp_path, BASE.format(beam=beam))
    out = subprocess.run([sys.executable, "-m", "mbseig", "modes", str(path)],
                         capture_output=True, text=True, timeout=60, check=False)
    assert out.returncode == 2
    lines = out.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"mbseig: {path}: ") and message in lines[0], \
        out.stderr
    with pytest.raises(CaseError):
        load_case(path)


def test_rotor_on_beam_station_and_point_reference(tmp_path):
    """A station is a frame (a `rotor` on it, a `{body = "bar.s", at}` spring end) and a point
    ("bar.s" as a `force` point): the model builds, the rotor's whirl stations start at the
    station's node, and a static tip force through the point "bar.s" gives the closed-form
    cantilever deflection F a³/(3 E I) at a = 0.5 (cubic elements are exact for a point load
    at a node: 1e-9 relative, asserted)."""
    text = BASE.format(beam='section = { shape = "circle", d = 0.02 }\n'
                            'theory = "euler-bernoulli"\nstations = { s = 0.5 }').replace(
        'stiffness = { parameter = "Omega", at = [0.0, 50.0], values = '
        '[[1, 1, 1, 0, 0, 0], [2, 2, 2, 0, 0, 0]] }', 'stiffness = [0, 0, 0, 0, 0, 0]')
    text += """[[forces]]
name = "wheel"
type = "rotor"
body = "bar.s"
axis = [1.0, 0.0, 0.0]
polar_inertia = 0.01
speed = "Omega"
[[forces]]
name = "tie"
type = "spring"
points = [{ body = "bar.s", at = [0.5, 0.0, 0.0] }, "A"]
stiffness = 0.0
[[forces]]
name = "push"
type = "force"
point = "bar.s"
vector = [0.0, 0.0, -10.0]
"""
    m = load_case(write_case(tmp_path, text))
    from mbseig.model.spatial_whirl import rotors

    wheel = next(r for r in rotors(m) if "wheel" in r.name)
    assert wheel.stations[0][0] == "station"
    eq = equilibrium(m)
    z = m.points["bar.s"](eq.q)[2]
    EI = 2.1e11 * np.pi * 0.02**4 / 64
    assert abs(z - (-10.0 * 0.5**3 / (3 * EI))) <= 1e-6 * abs(z)
    md = modes(linearize(m, eq))
    assert np.all(np.isfinite(md.eigenvalues))


JEFFCOTT = """schema_version = 1
dimension = 3
[parameters]
Omega = 100.0
[[bodies]]
name = "disk"
mass = 10.0
com = [0.0, 0.0, 0.0]
inertia = [0.2, 0.1, 0.1]
[[forces]]
name = "support"
type = "bushing"
bodies = ["ground", "disk"]
at = [0.0, 0.0, 0.0]
stiffness = [1e6, 1e6, 1e6, 1e4, 1e4, 1e4]
damping = [0.0, 200.0, 200.0, 0.0, 0.0, 0.0]
[[forces]]
name = "spin"
type = "rotor"
body = "disk"
axis = [1.0, 0.0, 0.0]
polar_inertia = 0.2
speed = "Omega"
"""


def test_unbalance_response_jeffcott_closed_form(tmp_path):
    """A disk of mass m on an isotropic support (k, c) at its centre of mass (a Jeffcott rotor:
    translation decoupled from tilt), unbalance m·e = 1e-3 kg m: the centre moves on a forward
    circle of complex amplitude X = m e Ω² / (k − m Ω² + i c Ω) (Genta, Dynamics of Rotating
    Systems, 2005, §3.3), X₂ = −i X₁; asserted 1e-10 relative at three speeds (below, near
    and above the critical speed sqrt(k/m) = 316.2 rad/s)."""
    from mbseig.studies.unbalance import unbalance_response

    path = write_case(tmp_path, JEFFCOTT)
    speeds = np.array([100.0, 316.0, 500.0])
    res = unbalance_response(path, "Omega", speeds, at="disk.0", unbalance=1e-3)
    m, k, c = 10.0, 1e6, 200.0
    X = 1e-3 * speeds**2 / (k - m * speeds**2 + 1j * c * speeds)
    j = 0  # the rotor's first station: the disk's centre of mass ("disk.0" is that point)
    assert res.stations[j].endswith("centre of mass")
    np.testing.assert_allclose(res.X1[:, j], X, rtol=1e-10)
    np.testing.assert_allclose(res.X2[:, j], -1j * X, rtol=1e-10)
    np.testing.assert_allclose(res.major[:, j], np.abs(X), rtol=1e-10)
    assert json.dumps(res.to_json()) and res.table().count("\n") == 3


def test_auto_refinement_in_3d(tmp_path):
    """`elements = "auto"` with `[refinement]` on the oblique cantilever: mbseig doubles the mesh
    until the lowest four frequencies change by less than the accuracy 1e-4; they then meet the
    closed forms of the case (Blevins table 8-1, both planes) within that accuracy."""
    text = (CASES / "cantilever_3d_oblique.toml").read_text()
    text = text.replace('elements = "n"', 'elements = "auto"').replace(
        "[expected]", "[refinement]\nmodes = 4\naccuracy = 1e-4\n\n[expected]")
    a = analyze(write_case(tmp_path, text))
    assert a.refinement is not None and a.refinement.as_dict()["converged"]
    from expected import expected_omega_n

    w = np.sort(expected_omega_n(a.model.expected, a.model.parameters))
    got = np.sort(a.modes.omega_n)[:4]
    assert np.all(np.abs(got - w) <= 1e-4 * w)
