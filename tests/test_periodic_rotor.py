"""An asymmetric rotor on anisotropic bearings (cases/asymmetric_rotor_anisotropic_bearings.toml):
unstable speed ranges from the Floquet multipliers.

References: with isotropic bearings (dk = 0) the equations are time-invariant in the frame
turning with the shaft (closed form in the case's description): the fixed-frame multipliers
are exp(s 2π/Ω) with s the roots of s⁴ + (w1² + w2² + 2Ω²) s² + (w1² − Ω²)(w2² − Ω²) = 0, and the
speed range w1 < Ω < w2 is unstable; with anisotropic bearings (no closed form) an independent
integration of m q'' + K(t) q = 0 in the fixed frame (scipy solve_ivp, DOP853, rtol 1e-12).
"""

import math

import numpy as np
import pytest
from conftest import CASES
from scipy.integrate import solve_ivp

from mbseig.casefile import read_case
from mbseig.studies.periodic import periodic_analysis

CASE = CASES / "asymmetric_rotor_anisotropic_bearings.toml"
M, KXI, KETA, KB = 1.0, 1100.0, 900.0, 1000.0  # the case's parameters
W1, W2 = math.sqrt((KETA + KB) / M), math.sqrt((KXI + KB) / M)


def rotating_frame_multipliers(Omega):
    """exp(s T), s the roots of the time-invariant rotating-frame quartic (closed form)."""
    a, b = W1 ** 2 + W2 ** 2 + 2 * Omega ** 2, (W1 ** 2 - Omega ** 2) * (W2 ** 2 - Omega ** 2)
    s = np.roots([1.0, 0.0, a, 0.0, b])
    return np.exp(s * 2 * math.pi / Omega)


def fixed_frame_multipliers(Omega, dk):
    """Eigenvalues of the monodromy of m q'' + K(t) q = 0 integrated on its own."""
    def f(t, x):
        c, s = math.cos(Omega * t), math.sin(Omega * t)
        Rt = np.array([[c, -s], [s, c]])
        K = Rt @ np.diag([KXI, KETA]) @ Rt.T + np.diag([KB - dk, KB + dk])
        A = np.block([[np.zeros((2, 2)), np.eye(2)], [-K / M, np.zeros((2, 2))]])
        return (A @ x.reshape(4, 4)).ravel()
    sol = solve_ivp(f, (0, 2 * math.pi / Omega), np.eye(4).ravel(), method="DOP853",
                    rtol=1e-12, atol=1e-14)
    return np.linalg.eigvals(sol.y[:, -1].reshape(4, 4))


def matched(a, b):
    """Largest distance between two multiplier sets, matched greedily."""
    b = list(b)
    worst = 0.0
    for x in a:
        j = int(np.argmin([abs(x - y) for y in b]))
        worst = max(worst, abs(x - b.pop(j)))
    return worst


def test_isotropic_limit_equals_rotating_frame_form():
    """dk = 0 at Ω = 44.7 (between w1 and w2): the four multipliers equal exp(s 2π/Ω) of the
    time-invariant rotating-frame form (closed form), 1e-8 (the case's rtol) relative to the
    largest; unstable with the bound far below the margin."""
    spec = read_case(CASE)
    a = periodic_analysis(spec, params={"dk": "0"}).floquet
    ref = rotating_frame_multipliers(44.7)
    assert a.multipliers.size == 4
    assert matched(a.multipliers, ref) <= 1e-8 * np.max(np.abs(ref))
    assert a.verdict == "unstable" and a.error_bound < 1e-3 * a.decided_by[3]


@pytest.mark.parametrize("edge", [W1, W2])
def test_isotropic_unstable_speed_range(edge):
    """The verdict changes at w1 and w2 (closed form, the case's isotropic_unstable_range):
    unstable just inside (1e-5 relative), critical (undamped, |μ| = 1) just outside."""
    spec = read_case(CASE)
    exp = spec.data["expected"]["isotropic_unstable_range"]
    assert min(abs(edge - e) for e in exp) <= 1e-12 * edge
    inside = 1 + 1e-5 if edge == W1 else 1 - 1e-5
    outside = 1 - 1e-5 if edge == W1 else 1 + 1e-5
    v_in = periodic_analysis(spec, params={"dk": "0", "Omega": repr(edge * inside)}).floquet
    v_out = periodic_analysis(spec, params={"dk": "0", "Omega": repr(edge * outside)}).floquet
    assert v_in.verdict == "unstable" and v_out.verdict == "critical"


def test_anisotropic_bearings_against_fixed_frame_integration():
    """The bundled case (dk = 200): every multiplier equals the independent fixed-frame
    integration's, 1e-8 relative to the largest; the verdict is the case's."""
    spec = read_case(CASE)
    a = periodic_analysis(spec).floquet
    ref = fixed_frame_multipliers(44.7, 200.0)
    assert matched(a.multipliers, ref) <= 1e-8 * np.max(np.abs(ref))
    exp = spec.data["expected"]
    assert a.verdict == exp["verdict"]
    assert a.spectral_radius == pytest.approx(exp["spectral_radius"], rel=exp["rtol"])


def test_anisotropic_unstable_ranges_confirmed_by_fixed_frame_integration():
    """The case's three unstable speed ranges with dk = 200 (located by mbseig's sweep): the
    independent fixed-frame integration is unstable 1e-4 inside each edge (max|μ| > 1 + 1e-3)
    and neutral 1e-4 outside (|max|μ| − 1| < 1e-9, undamped)."""
    ranges = read_case(CASE).data["expected"]["unstable_ranges"]
    assert len(ranges) == 3
    for lo, hi in ranges:
        for edge, inside in ((lo, 1 + 1e-4), (hi, 1 - 1e-4)):
            outside = 2 - inside
            assert np.max(np.abs(fixed_frame_multipliers(edge * inside, 200.0))) > 1 + 1e-3
            assert abs(np.max(np.abs(fixed_frame_multipliers(edge * outside, 200.0))) - 1) < 1e-9


def test_turning_anchors_do_not_make_the_time_sampling_fail(tmp_path):
    """Without the case's fixed "frame" corner, the turning anchors set the extent of the points
    and so every constraint's length scale, which then varies with t with kinks.  That scale only
    judges residuals: it is held at t = 0 (mbseig.model.timed._MEASURES), so the period is
    sampled as with the corner (the interpolant meets off-grid builds to 1e-12 with few
    samples, not 512 with an error of 3e-5) and the multipliers are the same to 1e-10 (both
    models are the same mechanics; the multipliers' own bounds are ~1e-12)."""
    from mbseig.studies.periodic import timed_model

    text = (CASES / "asymmetric_rotor_anisotropic_bearings.toml").read_text()
    start = text.index('[[points]]                     # a fixed frame corner')
    end = text.index("[[forces]]", start)
    path = tmp_path / "no_frame.toml"
    path.write_text(text[:start] + text[end:])
    spec = read_case(path)
    ref_spec = read_case(CASES / "asymmetric_rotor_anisotropic_bearings.toml")
    timed, _ = timed_model(spec)
    assert timed.samples < 512 and timed.interpolation_error <= 1e-12
    a, b = periodic_analysis(spec).floquet, periodic_analysis(ref_spec).floquet
    assert matched(a.multipliers, b.multipliers) <= 1e-10 * np.max(np.abs(b.multipliers))
