"""A singular dynamic stiffness on the excitation grid: the unbalance response at rest, at an
undamped critical speed (a resonance: flagged, null) and at a speed where Z is singular along a
mode the unbalance does not load (finite); the frequency response at a pole on the grid (a
pole, or the transfer function's limit where the input does not drive it or the output does not
see it).  References are closed forms evaluated in exact rational arithmetic from the same
double inputs; tolerances are the solve's own first-order error bounds
(mbseig.studies.harmonic: κδ of ‖x‖, and the contour's bound at a pole on the grid)."""

import json
import math
from fractions import Fraction

import numpy as np
import pytest

from conftest import CASES, write_case
from mbseig.cli import main
from mbseig.studies.harmonic import EPS, accuracy, solve_harmonic

RIGID = str(CASES / "rigid_rotor.toml")
M_ROTOR, KY, KZ = 20.0, 1e6, 1.6e6  # cases/rigid_rotor.toml


def run_json(capsys, argv):
    assert main(argv) == 0
    return json.loads(capsys.readouterr().out)


def _unitary(n, seed):
    rng = np.random.default_rng(seed)
    q, _ = np.linalg.qr(rng.standard_normal((n, n)) + 1j * rng.standard_normal((n, n)))
    return q


@pytest.mark.parametrize("last", [0.0, 1e-300, 1e-6])
def test_solve_harmonic_decides_from_the_singular_values(last):
    """Z = U diag(3, 2, 1, last) Vᴴ: with last = 0 (or below δw) Z is singular; a force in its
    range gives the minimum-norm solution V Σ⁺ Uᴴ f, one with a component along u₄ a resonance;
    with last = 1e-6 Z is regular and x = V Σ⁻¹ Uᴴ f.  Reference: the factors themselves (an
    independent path); tolerance: the reported first-order bound κδ (doubled for the second
    order and the rounding of the reference)."""
    U, V = _unitary(4, 1), _unitary(4, 2)
    s = np.array([3.0, 2.0, 1.0, last])
    Z = (U * s) @ V.conj().T
    w = float(np.linalg.norm(Z))
    f = U[:, :3] @ np.array([1.0, -2.0, 0.5j])  # no component along u₄
    h = solve_harmonic(Z, f, w, n=4)
    inv = np.where(s > accuracy(4) * w, 1 / np.where(s > 0, s, 1), 0.0)
    ref = V @ (inv * (U.conj().T @ f))
    assert h.status == ("regular" if last > accuracy(4) * w else "singular")
    assert h.free == (0 if last > accuracy(4) * w else 1)
    assert np.linalg.norm(h.x - ref) <= 2 * h.error * np.linalg.norm(ref)
    assert h.backward_error <= h.tolerance
    driven = f + 1e-9 * U[:, 3]
    r = solve_harmonic(Z, driven, w, n=4)
    if last > accuracy(4) * w:  # regular: the small component is simply amplified
        assert r.status == "regular" and np.linalg.norm(r.x - ref) > 1e-4
    else:
        assert r.status == "resonance" and r.x is None and r.backward_error > r.tolerance


def _rigid_closed_form(w, me, ky=KY, kz=KZ, cy=0.0, cz=0.0):
    """Rigid rotor, unbalance at the centre of mass midway between the bearings: the conical
    modes are not loaded and each lateral direction is a 1-DOF oscillator (Genta 2005 §4; the
    case's source):  X₁ = m e Ω² / (2kz − mΩ² + 2icz Ω) (e₁ = −z),
    X₂ = −i m e Ω² / (2ky − mΩ² + 2icy Ω) (e₂ = y).  Evaluated exactly from the double inputs;
    None where the denominator vanishes (an undamped critical speed)."""
    W, me, m = Fraction(w), Fraction(me), Fraction(M_ROTOR)
    out = []
    for k, c, factor in ((kz, cz, 1), (ky, cy, -1j)):
        re, im = 2 * Fraction(k) - m * W * W, 2 * Fraction(c) * W
        den = re * re + im * im
        if den == 0:
            out.append(None)
            continue
        F = me * W * W  # F / (re + i im) = F (re − i im) / den
        out.append(factor * complex(float(F * re / den), float(-F * im / den)))
    return out


def _amplitudes(row, key):
    a, ph = row[f"amplitude_{key}"], row[f"phase_{key}"]
    return [None if x is None else x * np.exp(1j * math.radians(p))
            for x, p in zip(a, ph, strict=True)]


def _check_rigid(out, me, **damping):
    """Every station of the rigid rotor moves with its centre (pure translation), so each
    station's (X₁, X₂) is the closed form; tolerance 2 κδ ‖x‖ with ‖x‖ = |(X₁, X₂)| (a
    translation moves one basic point of the natural coordinates) times ‖C_S‖ ≤ √(1 + 0.6²) <
    2 for a station within 0.6 m of it; plus 4ε for the amplitude/phase round trip."""
    speeds, solves = out["speed"], out["solve"]
    for row in out["stations"]:
        got1, got2 = _amplitudes(row, 1), _amplitudes(row, 2)
        for k, w in enumerate(speeds):
            X1, X2 = _rigid_closed_form(w, me, **damping)
            if out["resonance"][k]:
                assert got1[k] is None and got2[k] is None and row["major"][k] is None
                continue
            size = math.hypot(abs(X1), abs(X2))
            tol = 2 * 2 * solves[k]["error_bound"] * size + 4 * EPS * size
            assert abs(got1[k] - X1) <= tol and abs(got2[k] - X2) <= tol, (w, row["station"])


def test_rigid_rotor_at_rest_at_resonance_and_along_an_unloaded_mode(capsys):
    """``mbseig unbalance cases/rigid_rotor.toml --param Omega=0:800:9 --at rotor --me 2e-4``:
    Ω = 0 present and exactly 0 (no force, no solve); Ω = 400 rad/s = √(2kz/m) a resonance
    (z-cylindrical mode, undamped, driven: null and flagged); Ω = 100 = √(kx/m) finite (Z singular
    along the axial mode, which the lateral force does not load); every other speed the closed
    form."""
    out = run_json(capsys, ["unbalance", RIGID, "--param", "Omega=0:800:9", "--at", "rotor",
                            "--me", "2e-4", "--json"])
    speeds = out["speed"]
    assert speeds == [100.0 * k for k in range(9)]
    status = [s["status"] for s in out["solve"]]
    assert status[0] == "rest" and status[1] == "singular" and status[4] == "resonance"
    assert out["solve"][1]["free_directions"] == 1 and out["solve"][4]["free_directions"] == 1
    assert out["resonance"] == [k == 4 for k in range(9)]
    assert all(s == "regular" for k, s in enumerate(status) if k not in (0, 1, 4))
    for row in out["stations"]:
        assert row["amplitude_1"][0] == 0.0 and row["amplitude_2"][0] == 0.0
        assert row["major"][0] == 0.0
        assert row["amplitude_1"][1] > 0 and row["amplitude_2"][1] > 0
    assert out["solve"][1]["backward_error"] <= out["solve"][1]["tolerance"]
    assert out["solve"][4]["backward_error"] > 1e6 * out["solve"][4]["tolerance"]
    _check_rigid(out, 2e-4)


def test_isotropic_rotor_is_the_jeffcott_type_closed_form(capsys):
    """ky = kz = k: X₁ = m e Ω² / (2k − mΩ² + 2icΩ), X₂ = −i X₁ (the 2-DOF Jeffcott-type
    response).  Damped (c = 300 N s/m): finite at the critical speed 400 rad/s too; undamped:
    400 rad/s is a resonance with both lateral directions singular."""
    base = ["unbalance", RIGID, "--at", "rotor", "--me", "1e-3", "--json", "--param",
            "ky=1.6e6"]
    out = run_json(capsys, base + ["--param", "Omega=0:800:17", "--param", "cy=300",
                                   "--param", "cz=300"])
    assert not any(out["resonance"])
    k400 = out["speed"].index(400.0)
    assert out["solve"][k400]["status"] == "regular"
    _check_rigid(out, 1e-3, ky=1.6e6, cy=300.0, cz=300.0)
    X1 = _rigid_closed_form(400.0, 1e-3, ky=1.6e6, cy=300.0, cz=300.0)[0]
    assert X1 == pytest.approx(1e-3 * 400.0 / (2j * 300.0), rel=1e-15)  # m e Ω / 2ic
    out = run_json(capsys, base + ["--param", "Omega=300:500:3"])
    assert out["resonance"] == [False, True, False]
    assert out["solve"][1]["free_directions"] == 2
    _check_rigid(out, 1e-3, ky=1.6e6)


def test_a_speed_next_to_the_critical_speed_is_finite_within_its_bound():
    """Ω = 400 (1 + 1e-9): Z is regular (σ_min/w ≈ 1e-10 ≫ δ) and the amplitude (≈ 1e9 times
    the static one) agrees with the exact closed form within the reported bound κδ: the
    threshold does not swallow a finite response, and the bound is honest where it is large."""
    from mbseig.studies.unbalance import unbalance_response

    w = 400.0 * (1 + 1e-9)
    res = unbalance_response(RIGID, "Omega", [w], at="rotor", unbalance=2e-4)
    sol = res.solves[0]
    assert sol.status == "regular" and sol.sigma_min > 1e3 * sol.tolerance
    X1, X2 = _rigid_closed_form(w, 2e-4)
    assert abs(X1) > 1e3  # metres: the linear model's answer next to a critical speed
    size = math.hypot(abs(X1), abs(X2))
    assert sol.error < 1e-3
    for j in range(len(res.stations)):
        assert abs(res.X1[0, j] - X1) <= 2 * 2 * sol.error * size
        assert abs(res.X2[0, j] - X2) <= 2 * 2 * sol.error * size


def test_figures_mark_the_resonance(tmp_path):
    """The Bode diagram draws a red dashed line at the resonance and names it in its legend;
    the polar diagram names it in its legend; the CSV leaves its cells blank and says so."""
    from mbseig.plots import rotor
    from mbseig.studies.unbalance import unbalance_response

    res = unbalance_response(RIGID, "Omega", np.linspace(0, 800, 9), at="rotor",
                             unbalance=2e-4)
    assert res.resonance_values() == [400.0]
    fig = rotor.unbalance_bode(res, unit="rad/s")
    top = fig.axes[0]
    red = [ln for ln in top.get_lines() if ln.get_linestyle() == "--"
           and list(ln.get_xdata()) == [400.0, 400.0]]
    assert red and rotor.RESONANCE_LABEL in [t.get_text() for t in top.get_legend().get_texts()]
    polar = rotor.unbalance_polar(res, unit="rad/s")
    texts = [t.get_text() for t in polar.axes[0].get_legend().get_texts()]
    assert any("400" in t and rotor.RESONANCE_LABEL in t for t in texts)
    rows = res.write_csv(tmp_path / "u.csv").read_text().splitlines()
    at400 = [r.split(",") for r in rows[1:] if r.startswith("400.0,")]
    assert at400 and all(r[3:8] == [""] * 5 and r[-1] == "true" for r in at400)


# Two unit masses between walls, three springs k = (2π)² N/m: modes at 1 Hz (in phase) and
# √3 Hz (in antiphase).  "push a" is a force on a; "pair" the tension of the middle spring
# (pushes the masses apart: it does not drive the in-phase mode); "xa" the position of a;
# "stretch" the middle spring's length (it does not see the in-phase mode).
TWO_MASSES = """schema_version = 1
title = "two masses between walls"
dimension = 1
[parameters]
m = 1.0
k = 39.47841760435743
[[points]]
name = "wall1"
position = [0.0]
fixed = true
[[points]]
name = "a"
position = [1.0]
[[points]]
name = "b"
position = [2.0]
[[points]]
name = "wall2"
position = [3.0]
fixed = true
[[masses]]
point = "a"
mass = "m"
[[masses]]
point = "b"
mass = "m"
[[forces]]
name = "s1"
type = "spring"
points = ["wall1", "a"]
stiffness = "k"
[[forces]]
name = "s2"
type = "spring"
points = ["a", "b"]
stiffness = "k"
[[forces]]
name = "s3"
type = "spring"
points = ["b", "wall2"]
stiffness = "k"
[[inputs]]
name = "push a"
point = "a"
direction = [1.0]
[[inputs]]
name = "pair"
element = "s2"
[[outputs]]
name = "xa"
quantity = "position"
point = "a"
direction = [1.0]
[[outputs]]
name = "stretch"
quantity = "length"
element = "s2"
"""
K = Fraction(39.47841760435743)
B = {"push a": (1, 0), "pair": (1, -1)}  # force on (a, b)
C = {"xa": (1, 0), "stretch": (-1, 1)}


def _two_mass(f, u, y, walls):
    """x = (K − ω²M)⁻¹ b by Cramer's rule in exact arithmetic, K = [[2k, −k], [−k, 2k]] between
    walls ([[k, −k], [−k, k]] free); returns (G = c·x, ‖x‖), or None at a pole."""
    w2 = Fraction(2 * math.pi * f) ** 2
    d = (2 if walls else 1) * K - w2
    det = d * d - K * K
    if det == 0:
        return None
    (b1, b2), (c1, c2) = B[u], C[y]
    x1, x2 = (d * b1 + K * b2) / det, (K * b1 + d * b2) / det
    return float(c1 * x1 + c2 * x2), math.hypot(float(x1), float(x2))


LIMITS = {  # the transfer function's limit at the pole on the grid (closed form)
    (True, "pair", "xa"): 1 / (2 * K), (True, "push a", "stretch"): -1 / (2 * K),
    (True, "pair", "stretch"): -1 / K, (False, "pair", "xa"): 1 / (2 * K),
    (False, "push a", "stretch"): -1 / (2 * K), (False, "pair", "stretch"): -1 / K}


@pytest.mark.parametrize("walls", [True, False])
@pytest.mark.parametrize("u, y", [("push a", "xa"), ("pair", "xa"), ("push a", "stretch"),
                                  ("pair", "stretch")])
def test_frf_at_a_pole_on_the_grid(tmp_path, capsys, walls, u, y):
    """``mbseig frf --hz 0:2:3`` (0, 1, 2 Hz).  Between walls the in-phase mode is at 1 Hz: a
    pole where "push a" drives it and "xa" sees it, the transfer function's limit otherwise
    (closed form 1/(3k − ω²) at ω² = k, ...).  Free (no wall springs), s = 0 is a double
    (rigid-body) eigenvalue: a pole for push a → xa, the limit of the static deflection for an
    internal pair or an output blind to translation.  Regular points: the closed form within
    2κδ‖x‖ (κ = w/σ_min of K − ω²M, an independent evaluation); at the pole on the grid:
    within the reported contour bound."""
    path = write_case(tmp_path, TWO_MASSES if walls else _free_text())
    out = run_json(capsys, ["frf", str(path), "--input", u, "--output", y, "--hz", "0:2:3",
                            "--json"])
    pole_at = 1 if walls else 0
    delta = accuracy(2)
    Km = np.array([[2.0, -1.0], [-1.0, 2.0]]) if walls else np.array([[1.0, -1.0], [-1.0, 1.0]])
    Km *= float(K)
    for i, f in enumerate(out["freq_hz"]):
        if i == pole_at:
            [item] = out["singular"]
            assert item["freq_hz"] == f
            limit = LIMITS.get((walls, u, y))
            if limit is None:
                assert out["response"][i] is None and out["resonance"][i]
                assert item["status"] == "pole" and item["principal"] > 1e6 * item["error"]
            else:
                assert not out["resonance"][i] and item["status"] == "limit"
                got = complex(*out["response"][i])
                assert abs(got - float(limit)) <= item["error"] + 4 * EPS * abs(float(limit))
            continue
        G, xn = _two_mass(f, u, y, walls)
        w2 = (2 * math.pi * f) ** 2
        Z = Km - w2 * np.eye(2)
        w = np.linalg.norm(Km) + w2 * math.sqrt(2)
        kappa = w / np.linalg.svd(Z, compute_uv=False)[-1]
        got = complex(*out["response"][i])
        assert abs(got - G) <= 2 * kappa * delta * math.hypot(*C[y]) * xn + 4 * EPS * abs(G)


def _free_text():
    text = TWO_MASSES.replace("two masses between walls", "two free masses")
    for name, pts in (("s1", '["wall1", "a"]'), ("s3", '["b", "wall2"]')):
        block = (f'[[forces]]\nname = "{name}"\ntype = "spring"\npoints = {pts}\n'
                 f'stiffness = "k"\n')
        assert block in text
        text = text.replace(block, "")
    return text


def test_frf_outputs_mark_the_pole(tmp_path, capsys):
    """The text names the pole on the grid, the CSV leaves its values blank, the Bode diagram
    draws it as a red dashed line."""
    from mbseig.casefile import load_case
    from mbseig.linear import linearize
    from mbseig.statics import equilibrium
    from mbseig.studies.frf import bode_figure, frf

    path = write_case(tmp_path, TWO_MASSES)
    assert main(["frf", str(path), "--input", "push a", "--output", "xa", "--hz", "0:2:5",
                 "--out", str(tmp_path / "o")]) == 0
    text = capsys.readouterr().out
    assert "pole on the grid at 1 Hz: the response is unbounded" in text
    rows = (tmp_path / "o" / "frf.csv").read_text().splitlines()
    assert rows[0].endswith(",resonance") and rows[3] == "1,,,,,true"
    model = load_case(path)
    lin = linearize(model, equilibrium(model))
    fig = bode_figure(frf(lin, "push a", "xa", freq_hz=[0.5, 1.0, 1.5]))
    assert any(ln.get_color() == "tab:red" and list(ln.get_xdata()) == [1.0, 1.0]
               for ln in fig.axes[0].get_lines())
