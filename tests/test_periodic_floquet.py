"""Floquet analysis: each reference value names its source and tolerance.

Mathieu characteristic values: scipy.special.mathieu_a / mathieu_b (DLMF §28.2 standard form);
parameter mappings in the reference systems below (their docstring).
"""

import json
import math

import numpy as np
import pytest
import scipy.linalg as la
from scipy.integrate import solve_ivp
from scipy.optimize import brentq
from scipy.special import mathieu_a, mathieu_b

from mbseig.errors import CaseError
from mbseig.studies.floquet import (
    FloquetError,
    floquet,
    floquet_partial,
    frozen_time_eigenvalues,
    monodromy,
)
from mbseig.studies.floquet_paths import (
    constrained_system,
    first_order,
    floquet_of_orbit,
    periodic_orbit,
)
from mbseig.plots.charts import chart_figure
from mbseig.studies.floquet_sweep import stability_chart, verdict_changes

# ---- reference systems ------------------------------------------------------------------
_REFERENCE_SYSTEMS = """Reference periodic systems and their mappings onto the Mathieu equation.

Mathieu's equation in the standard form of DLMF §28.2 (https://dlmf.nist.gov/28.2.E1):

    w'' + (a − 2 q cos 2z) w = 0,          period π in z.

Its stability boundaries are the characteristic values a_m(q) (even solutions, scipy.special.
mathieu_a) and b_m(q) (odd, mathieu_b): on a_m, b_m with m odd the solution has period 2π
(multiplier −1, a flip); with m even period π (multiplier +1, a fold).  The first
(principal) parametric-resonance tongue is b_1(q) < a < a_1(q); a < a_0(q) is unstable.

Damped form used here:  x'' + 2ζ x' + (a − 2q cos 2t) x = 0.  The substitution x = e^(−ζt) w
gives w'' + (a − ζ² − 2q cos 2t) w = 0 (Nayfeh & Mook, Nonlinear Oscillations, 1979, §5.3), so
the multipliers of the damped equation are exactly e^(−ζπ) times those of the undamped equation
with a − ζ², and det Φ = e^(−2ζπ).

Pendulum on a vertically driven pivot, pivot height y_p = A cos ωt, length l, gravity g, angle θ
from the hanging position, viscous damping c per unit inertia:

    θ'' + c θ' + ((g + ÿ_p)/l) sin θ = 0,        ÿ_p = −A ω² cos ωt.

Hanging (θ small), with τ = ωt/2:  θ_ττ + (4g/(lω²) − (4A/l) cos 2τ) θ = 0, i.e.

    a = 4 g / (l ω²) = 4 ω₀²/ω²,      q = 2 A / l      (ω₀² = g/l).

Principal resonance at ω ≈ 2ω₀ (a ≈ 1), between b_1(q) and a_1(q).
Inverted (θ = π + φ):  φ_ττ + (−4g/(lω²) + (4A/l) cos 2τ) φ = 0, i.e. a = −4g/(lω²), q = −2A/l;
the stability chart is symmetric in q (z → z + π/2), so q = 2A/l.  The inverted position is
stable for a_0(q) < a < b_1(q).  With a_0(q) = −q²/2 + 7q⁴/128 − 29q⁶/2304 + … (DLMF 28.6.1)
the lower boundary, a = a_0(q), reads 4g/(lω²) = q²/2 − 7q⁴/128 + …, to leading order
(Aω)² = 2 g l — Kapitza's criterion (Aω)² > 2gl (Landau & Lifshitz, Mechanics, §30); the exact
boundary is ω*² = −4g/(l a_0(2A/l)).

Bolotin's column (Bolotin, The Dynamic Stability of Elastic Systems, 1964, §2): a simply
supported column, length L, bending stiffness EI, mass per length m, axial load
P(t) = P_0 + P_t cos θt.  The modes sin(jπx/L) decouple; mode j obeys

    f_j'' + Ω_j² (1 − 2 β_j cos θt) f_j = 0,
    Ω_j = ω_j √(1 − P_0/P_j),  ω_j = (jπ/L)² √(EI/m),  P_j = j² π² EI/L²,  β_j = P_t/(2(P_j − P_0)).

With τ = θt/2:  a = 4Ω_j²/θ², q = 2 β_j a = 4Ω_j² β_j/θ².  The principal region (mode 1) is
bounded by a = a_1(q), a = b_1(q); Bolotin's first approximation a ≈ 1 ± q gives

    θ* = 2 Ω_1 √(1 ± β_1)            (his eq. for the principal region of instability),

exact to O(β²); the exact boundary solves a = a_1(β a) (resp. b_1) for a, θ* = 2Ω_1/√a.
"""



def mathieu(a, q, zeta=0.0):
    """(A, T): x'' + 2ζx' + (a − 2q cos 2t) x = 0 as a first-order system, T = π."""
    def A(t):
        return np.array([[0.0, 1.0], [-(a - 2 * q * math.cos(2 * t)), -2 * zeta]])
    return A, math.pi


def pendulum_pivot(omega, *, amplitude, length=1.0, g=9.81, damping=0.0, inverted=False):
    """(A, T): the pendulum on a pivot y_p = A cos ωt, linearized about hanging (or inverted),
    state [θ, θ'] (or [φ, φ']); T = 2π/ω."""
    s = -1.0 if inverted else 1.0

    def A(t):
        k = s * (g - amplitude * omega ** 2 * math.cos(omega * t)) / length
        return np.array([[0.0, 1.0], [-k, -damping]])
    return A, 2 * math.pi / omega


def column_modes(theta, *, P0, Pt, EI=1.0, m=1.0, L=1.0, modes=2, damping=0.0):
    """(M, C, K) callables of the Galerkin column (modes sin(jπx/L), generalized coordinates
    f_j) and the period 2π/θ: M = (mL/2) I, K(t) = (L/2) diag(EI k_j⁴ − P(t) k_j²), k_j = jπ/L."""
    kj = np.arange(1, modes + 1) * math.pi / L
    Mm = 0.5 * m * L * np.eye(modes)
    Cm = damping * Mm

    def K(t):
        P = P0 + Pt * math.cos(theta * t)
        return 0.5 * L * np.diag(EI * kj ** 4 - P * kj ** 2)
    return (lambda t: Mm), (lambda t: Cm), K, 2 * math.pi / theta


def rotating_wire(Omega, *, k=1.0, c=0.0, mass=1.0):
    """A bead (mass m) on a straight wire through the origin turning at Ω in the plane, tied to
    the origin by an isotropic spring k and damper c: coordinates q = (x, y), rheonomic
    constraint Φ(q, t) = −sin(Ωt) x + cos(Ωt) y = 0, reference motion q* = 0 (λ* = 0).

    Returns (M, C, K, Φ_q, Φ̇_q, T) callables, T = 2π/Ω.  Along the wire, r'' + (c/m) r' +
    (k/m − Ω²) r = 0 (time-invariant): multipliers exp(s T), s² + (c/m)s + k/m − Ω² = 0.
    The centrifugal term −Ω² r comes entirely from Ṅ: a projection that ignored Ṅ would miss it.
    """
    Mm, Cm, Km = mass * np.eye(2), c * np.eye(2), k * np.eye(2)

    def phi_q(t):
        return np.array([[-math.sin(Omega * t), math.cos(Omega * t)]])

    def phi_q_dot(t):
        return Omega * np.array([[-math.cos(Omega * t), -math.sin(Omega * t)]])

    return (lambda t: Mm), (lambda t: Cm), (lambda t: Km), phi_q, phi_q_dot, 2 * math.pi / Omega


G, L = 9.81, 1.0


# ---- closed forms --------------------------------------------------------------------------------
def test_constant_matrix_monodromy_is_expm():
    """Constant A: Φ = expm(A T) (closed form), to 1e-12 relative; exponents = eig(A)."""
    rng = np.random.default_rng(1)
    A0 = rng.standard_normal((4, 4)) - 1.5 * np.eye(4)
    T = 0.7
    res = floquet(lambda t: A0, T)
    ref = la.expm(A0 * T)
    assert np.linalg.norm(res.monodromy - ref) <= 1e-12 * np.linalg.norm(ref)
    s = np.sort_complex(la.eigvals(A0))
    assert np.allclose(np.sort_complex(res.exponents), s, atol=1e-10)  # |Im s| < π/T here
    assert res.verdict == ("stable" if np.all(s.real < 0) else "unstable")


def test_liouville_identity_damped_mathieu():
    """det Φ = exp(∫ tr A) = exp(−2ζπ) (closed form: tr A = −2ζ); mismatch reported < 1e-12."""
    zeta = 0.07
    res = floquet(*mathieu(2.3, 0.8, zeta))
    assert res.det_check < 1e-12
    assert abs(res.trace_integral + 2 * zeta * math.pi) < 1e-13
    assert abs(np.prod(res.multipliers).real / math.exp(-2 * zeta * math.pi) - 1) < 1e-11


def test_damped_mathieu_equals_scaled_undamped():
    """x = e^(−ζt) w (Nayfeh & Mook §5.3): μ_damped = e^(−ζπ) μ_undamped(a − ζ²), to 1e-9."""
    a, q, zeta = 1.1, 0.4, 0.05
    d = floquet(*mathieu(a, q, zeta))
    u = floquet(*mathieu(a - zeta ** 2, q))
    assert np.allclose(np.sort_complex(d.multipliers),
                       np.sort_complex(math.exp(-zeta * math.pi) * u.multipliers), atol=1e-9)
    assert np.all(d.error_bounds < 1e-9)


def test_error_bound_and_verdict_tolerance():
    """Undamped Mathieu inside the stable region: |μ| = 1 exactly (Hamiltonian, det Φ = 1), so
    the honest verdict is critical with the bound covering |μ| − 1; in the tongue unstable with
    margin far above the bound."""
    inside = floquet(*mathieu(2.0, 0.5))  # between a_1(0.5) ≈ 1.46 and b_2(0.5) ≈ 3.92
    assert inside.verdict == "critical"
    assert np.all(np.abs(np.abs(inside.multipliers) - 1) <= inside.error_bounds)
    tongue = floquet(*mathieu(1.0, 0.5))
    k, mod, bound, margin = tongue.decided_by
    assert tongue.verdict == "unstable" and margin > 1e6 * bound


def test_json_has_design_fields():
    """DESIGN §8: "floquet": {period, multipliers [[re, im]], exponents, error_bound, verdict}."""
    res = floquet(*mathieu(1.0, 0.3, 0.01))
    out = json.loads(res.to_json())["floquet"]
    assert {"period", "multipliers", "exponents", "error_bound", "verdict"} <= set(out)
    assert out["period"] == pytest.approx(math.pi, rel=1e-15)
    assert all(len(m) == 2 for m in out["multipliers"]) and len(out["multipliers"]) == 2
    assert abs(out["exponents"][0][1]) <= math.pi / out["period"] + 1e-12
    assert out["verdict"] in ("stable", "critical", "unstable")
    assert isinstance(out["error_bound"], float)


# ---- driven pendulum -----------------------------------------------------------------------------
def test_hanging_pendulum_tongue_in_frequency():
    """First tongue of the hanging pendulum (q = 2A/l = 0.2): ω = 2ω₀/√a on a = b_1(q) and
    a = a_1(q) (scipy mathieu_b / mathieu_a), both flips, located to 1e-8 relative."""
    A = 0.1
    q = 2 * A / L
    ref = sorted(math.sqrt(4 * G / (L * c)) for c in (mathieu_a(1, q), mathieu_b(1, q)))
    w0 = math.sqrt(G / L)
    grid = np.linspace(1.6 * w0, 2.4 * w0, 9)
    found = verdict_changes(lambda w: pendulum_pivot(w, amplitude=A), grid)
    assert [b.kind for b in found] == ["flip", "flip"]
    assert [b.stability for b in found] == ["loss", "recovery"]
    for b, r in zip(found, ref, strict=True):
        assert abs(b.value / r - 1) < 1e-8, (b, r)


def test_tongue_boundary_in_amplitude_against_brentq_on_characteristic_value():
    """At fixed ω (a = 4g/(lω²) = 1.15), the amplitude where the tongue opens: a = a_1(q),
    q = 2A/l; reference q* from brentq on mathieu_a(1, q) − a (independent of any ODE), 1e-8."""
    a = 1.15
    w = math.sqrt(4 * G / (L * a))
    q_ref = brentq(lambda q: mathieu_a(1, q) - a, 1e-3, 1.0, xtol=1e-15, rtol=1e-15)
    amps = np.linspace(0.02, 0.3, 8)
    found = verdict_changes(lambda amp: pendulum_pivot(w, amplitude=amp), amps)
    assert len(found) == 1 and found[0].kind == "flip" and found[0].stability == "loss"
    assert abs(2 * found[0].value / L / q_ref - 1) < 1e-8


def test_frozen_time_eigenvalues_are_wrong_hanging():
    """ω = 2ω₀, A/l = 0.1 (q = 0.2, a = 1: the tongue's centre), damping 0.05/s: every frozen
    instant has g + ÿ_p > 0 (Aω² = 0.4 g) and damped eigenvalues, Re s < 0; Floquet: unstable
    (growth ≈ e^(πq/2) per period ≫ the damping's e^(−cT/2))."""
    w = 2 * math.sqrt(G / L)
    A, T = pendulum_pivot(w, amplitude=0.1, damping=0.05)
    _, s = frozen_time_eigenvalues(A, T)
    assert np.max(s.real) < 0  # frozen: stable at every instant (wrong)
    assert floquet(A, T).verdict == "unstable"  # Floquet: unstable (right)


def test_inverted_pendulum_kapitza_boundary():
    """Inverted, A/l = 0.1 (q = 0.2): stable above ω* = √(−4g/(l a_0(q))) (fold, μ → +1),
    located to 1e-8 against scipy mathieu_a(0, q).  Kapitza's (Aω)² = 2gl is its leading order:
    ω*/ω_K = (1 − 7q²/64 + 29q⁴/1152)^(−1/2) from DLMF 28.6.1 to O(q⁶) (< 1e-6 here)."""
    amp = 0.1
    q = 2 * amp / L
    w_exact = math.sqrt(-4 * G / (L * mathieu_a(0, q)))
    w_kapitza = math.sqrt(2 * G * L) / amp
    grid = np.linspace(0.9 * w_kapitza, 1.1 * w_kapitza, 5)
    found = verdict_changes(lambda w: pendulum_pivot(w, amplitude=amp, inverted=True), grid)
    assert len(found) == 1
    b = found[0]
    assert b.kind == "fold" and b.stability == "recovery"
    assert abs(b.value / w_exact - 1) < 1e-8
    series = (1 - 7 * q ** 2 / 64 + 29 * q ** 4 / 1152) ** -0.5
    assert abs(b.value / w_kapitza - series) < 1e-6
    assert b.value / w_kapitza - 1 > 1e-3  # the approximation is off by ≈ 7q²/128 = 0.22 %


def test_frozen_time_eigenvalues_are_wrong_inverted():
    """Inverted above Kapitza's boundary with light damping: Floquet stable; frozen instants
    (and the unshaken, averaged pendulum) have a real eigenvalue > 0."""
    amp, c = 0.1, 0.2
    w = 1.3 * math.sqrt(2 * G * L) / amp
    A, T = pendulum_pivot(w, amplitude=amp, damping=c, inverted=True)
    res = floquet(A, T)
    assert res.verdict == "stable"
    _, s = frozen_time_eigenvalues(A, T)
    assert np.mean(np.max(s.real, axis=1) > 0) > 0.4  # frozen: unstable at many instants
    averaged = np.array([[0, 1], [G / L, -c]])
    assert np.max(la.eigvals(averaged).real) > 0


# ---- constrained linearization -------------------------------------------------------------------
def test_rotating_wire_closed_form_and_no_spurious_multipliers():
    """Bead on a wire turning at Ω (rheonomic constraint): 2 multipliers (not 4), equal to
    exp(s T), s² + (c/m)s + k/m − Ω² = 0 (closed form, periodic_cases.rotating_wire), 1e-9;
    the basis turns a full revolution (16 Procrustes segments) and comes back, R = [1]."""
    for Omega, k, c in ((0.8, 1.0, 0.1), (1.5, 1.0, 0.1)):
        M, C, K, pq, pqd, T = rotating_wire(Omega, k=k, c=c)
        cs = constrained_system(M, C, K, pq, pqd, T)
        res = floquet(cs.system)
        ref = np.exp(np.roots([1, c, k - Omega ** 2]) * T)
        assert res.multipliers.size == 2
        assert np.allclose(np.sort_complex(res.multipliers), np.sort_complex(ref.astype(complex)),
                           rtol=1e-9, atol=1e-11)
        assert abs(cs.path.holonomy[0, 0] - 1) < 1e-12
        assert res.det_check < 1e-11
        assert res.verdict == ("stable" if Omega ** 2 < k else "unstable")


def test_null_space_derivative_against_central_differences():
    """Ṅ of the Procrustes path against central differences of N(t) (h = 1e-5: O(h²) ≈ 1e-10)
    and Φ_q N = 0, NᵀN = I on a 3-coordinate, 1-constraint rheonomic Jacobian."""
    def pq(t):
        return np.array([[1 + 0.3 * math.sin(t), math.cos(2 * t), 0.5]])

    def pqd(t):
        return np.array([[0.3 * math.cos(t), -2 * math.sin(2 * t), 0.0]])

    from mbseig.studies.floquet_paths import null_space_path
    path = null_space_path(pq, pqd, 2 * math.pi, segments=8)
    h = 1e-5
    for t in (0.3, 1.9, 4.4):
        k = path.segment(t)
        N, Nd = path.derivative(t, k)
        fd = (path.basis(t + h, k) - path.basis(t - h, k)) / (2 * h)
        assert np.abs(Nd - fd).max() < 1e-8
        assert np.abs(pq(t) @ N).max() < 1e-13
        assert np.abs(N.T @ N - np.eye(2)).max() < 1e-13


def test_pendulum_in_natural_coordinates_matches_angle_form():
    """Point mass on a distance constraint to the shaken pivot (natural coordinates, q = (x, y)):
    K = Σλ*∇²Φ = 2λ* I with λ* = m(g + ÿ_p)/(2l) (the constraint-force stiffness); the
    multipliers equal those of the angle form (independent formulation), 1e-9."""
    w, amp, m = 2.1 * math.sqrt(G / L), 0.08, 2.0

    def lam(t):
        return m * (G - amp * w ** 2 * math.cos(w * t)) / (2 * L)

    cs = constrained_system(lambda t: m * np.eye(2), lambda t: np.zeros((2, 2)),
                            lambda t: 2 * lam(t) * np.eye(2), lambda t: np.array([[0.0, -2 * L]]),
                            lambda t: np.zeros((1, 2)), 2 * math.pi / w, segments=2)
    nat = floquet(cs.system)
    ang = floquet(*pendulum_pivot(w, amplitude=amp))
    assert nat.multipliers.size == 2
    assert np.allclose(np.sort_complex(nat.multipliers), np.sort_complex(ang.multipliers),
                       atol=1e-9)


def test_bolotin_column_principal_resonance():
    """Pinned column, P(t) = P0 + Pt cos θt, first Galerkin mode (the modes decouple exactly;
    M q̈ + K(t) q = 0 in first-order form): the principal region of mode 1 between θ = 2Ω₁/√a
    with a = b_1(βa) and a = a_1(βa) (exact, brentq on scipy's characteristic values), 1e-8;
    Bolotin's θ* = 2Ω₁√(1 ± β) within β² (its error is O(β²))."""
    PE = math.pi ** 2
    P0, Pt = 0.3 * PE, 0.2 * PE
    beta = Pt / (2 * (PE - P0))
    Om = math.pi ** 2 * math.sqrt(1 - P0 / PE)

    def root(char):
        a = brentq(lambda a: char(1, beta * a) - a, 0.5, 2.0, xtol=1e-15, rtol=1e-15)
        return 2 * Om / math.sqrt(a)

    exact = sorted([root(mathieu_a), root(mathieu_b)])
    bolotin = sorted([2 * Om * math.sqrt(1 - beta), 2 * Om * math.sqrt(1 + beta)])

    def build(theta):
        M, C, K, T = column_modes(theta, P0=P0, Pt=Pt, modes=1)
        return first_order(M, C, K), T

    found = verdict_changes(build, np.linspace(0.8 * 2 * Om, 1.2 * 2 * Om, 5))
    assert [b.kind for b in found] == ["flip", "flip"]
    for b, e, approx in zip(found, exact, bolotin, strict=True):
        assert abs(b.value / e - 1) < 1e-8
        assert abs(approx / e - 1) < beta ** 2


# ---- shooting ------------------------------------------------------------------------------------
def _duffing(c=0.2, beta=0.1, F=0.3, w=1.2):
    """x'' + c x' + x + β x³ = F cos ωt.  β = 0.1: one periodic response (the backbone
    ω² ≈ 1 + ¾βX² reaches ω = 1.2 at X ≈ 2.4, beyond the linear peak F/(cω) = 1.25); with
    β = 0.5 the response is bistable and shooting from rest stalls, said so in its message."""
    def f(x, t):
        return np.array([x[1], -c * x[1] - x[0] - beta * x[0] ** 3 + F * math.cos(w * t)])

    def jac(x, t):
        return np.array([[0.0, 1.0], [-1 - 3 * beta * x[0] ** 2, -c]])
    return f, jac, 2 * math.pi / w


def test_shooting_linear_forced_oscillator_closed_form():
    """β = 0: x = X cos(ωt − φ), X = F/√((1−ω²)² + (cω)²), tan φ = cω/(1−ω²) (closed form)."""
    c, F, w = 0.2, 0.3, 1.2
    f, jac, T = _duffing(c=c, beta=0.0, F=F, w=w)
    orb = periodic_orbit(f, [0.0, 0.0], T, jac=jac)
    X = F / math.hypot(1 - w ** 2, c * w)
    phi = math.atan2(c * w, 1 - w ** 2)
    assert np.allclose(orb.x0, [X * math.cos(phi), X * w * math.sin(phi)], atol=1e-9)


def test_shooting_duffing_against_long_simulation_and_liouville():
    """Duffing: shooting's x*(0) against a 60-period simulation from rest (transients decay as
    e^(−ct/2): ≈ 3e-14 after 60 T), 1e-8; multipliers: det Φ = e^(−cT) (tr ∂f/∂x = −c)."""
    c = 0.2
    f, jac, T = _duffing(c=c)
    orb = periodic_orbit(f, [0.0, 0.0], T, jac=jac)
    sol = solve_ivp(lambda t, x: f(x, t), (0, 60 * T), [0.0, 0.0], method="DOP853",
                    rtol=1e-12, atol=1e-14)
    assert np.allclose(orb.x0, sol.y[:, -1], atol=1e-8)
    res = floquet_of_orbit(f, orb, jac=jac)
    assert abs(np.prod(res.multipliers).real / math.exp(-c * T) - 1) < 1e-10
    assert res.verdict == "stable" and res.det_check < 1e-9


def test_shooting_failure_says_what_from_where_residual():
    """x' = 1 has no periodic solution: the error names shooting, the start and the residual."""
    with pytest.raises(FloquetError) as err:
        periodic_orbit(lambda x, t: np.ones(1), [0.5], 2.0, jac=lambda x, t: np.zeros((1, 1)))
    msg = str(err.value)
    assert "shooting" in msg and "[0.5]" in msg and "‖x(T) − x(0)‖ = 2" in msg


# ---- partial method, chart, bad input ------------------------------------------------------------
def test_arnoldi_largest_multipliers_match_full():
    """20 damped Mathieu oscillators (n = 40) mixed by an orthogonal similarity: the 2 largest
    |μ| by Arnoldi on the monodromy operator equal those of the full monodromy, 1e-8."""
    rng = np.random.default_rng(3)
    m = 20
    a = np.linspace(0.3, 3.0, m)
    zeta = np.linspace(0.02, 0.2, m)
    Q = la.qr(rng.standard_normal((2 * m, 2 * m)))[0]
    A0 = Q @ la.block_diag(*[np.array([[0, 1], [-a[i], -2 * zeta[i]]]) for i in range(m)]) @ Q.T
    A1 = Q @ la.block_diag(*[np.array([[0, 0], [0.6, 0]]) for _ in range(m)]) @ Q.T

    def A(t):
        return A0 + math.cos(2 * t) * A1

    part = floquet_partial(A, math.pi, k=2, rtol=1e-11)
    full = monodromy(A, math.pi, rtol=1e-11)
    mu = la.eigvals(full)
    top = mu[np.argsort(-np.abs(mu))[:2]]
    assert np.allclose(np.sort(np.abs(part.multipliers)), np.sort(np.abs(top)), rtol=1e-8)
    assert np.all(part.residuals < 1e-8)


def test_ince_strutt_chart_against_characteristic_values():
    """Undamped Mathieu chart: unstable ⇔ a < a_0(q) or b_m(q) < a < a_m(q) (m = 1, 2), at grid
    points farther than 0.02 from every boundary (scipy mathieu_a / mathieu_b)."""
    qs = np.linspace(0.1, 1.5, 5)
    avals = np.linspace(-0.6, 4.6, 9)
    chart = stability_chart(lambda a, q: mathieu(a, q), avals, qs, names=("a", "q"),
                            rtols=(1e-6, 1e-8))
    checked = 0
    for i, a in enumerate(avals):
        for j, q in enumerate(qs):
            edges = [mathieu_a(0, q), mathieu_b(1, q), mathieu_a(1, q), mathieu_b(2, q),
                     mathieu_a(2, q)]
            if min(abs(a - e) for e in edges) < 0.02 or a > mathieu_b(3, q) - 0.02:
                continue
            unstable = a < edges[0] or edges[1] < a < edges[2] or edges[3] < a < edges[4]
            assert (chart.verdicts[i, j] == "unstable") == unstable, (a, q)
            checked += 1
    assert checked > 30
    import matplotlib
    backend = matplotlib.get_backend()
    fig = chart_figure(chart)
    assert fig.axes and matplotlib.get_backend() == backend


def test_bad_period_and_non_repeating_motion():
    """A period that is not positive: CaseError naming motion.period; a constraint Jacobian that
    does not repeat with the stated period: FloquetError saying so."""
    with pytest.raises(CaseError, match="motion.period: period must be a positive"):
        floquet(lambda t: np.eye(2), -1.0)
    M, C, K, pq, pqd, T = rotating_wire(1.0)
    with pytest.raises(FloquetError, match="does not repeat"):
        constrained_system(M, C, K, pq, pqd, 0.8 * T)
