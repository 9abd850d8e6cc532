"""Cases where a naive method gets the stability verdict wrong, and what mbseig says instead.

Each function returns a :class:`FailCase`: the system, the naive method and its answer, mbseig's
answer, and the reference (closed form or a theorem) that decides which one is right.  They are
asserted in ``tests/test_failures.py`` and tabulated by ``mbseig bench`` (section "Stability
where methods fail" of reports/benchmarks.md).

Naive methods, as commonly written:

* ``naive_companion``: A = [[0, I], [−M⁻¹Q, −M⁻¹P]] with M⁻¹ formed explicitly, no scaling,
  ``numpy.linalg.eig``; then
* ``naive_verdict``: Re s > 0 unstable, Re s < 0 stable, exactly 0 critical (no tolerance).
"""

from __future__ import annotations

import warnings

import numpy as np
import scipy.linalg as sla
from scipy.optimize import linear_sum_assignment

from ..casefile import load_case
from ..check import check_modes
from ..linear import linearize
from ..modal import modes
from ..statics import equilibrium
from .cases import case_path
from .failrecord import FailCase

__all__ = ["FailCase", "ALL", "naive_companion", "naive_verdict", "run_all"]


def naive_companion(M, P, Q):
    """Eigenvalues of [[0, I], [−M⁻¹Q, −M⁻¹P]] (explicit inverse, unscaled, LAPACK geev)."""
    n = M.shape[0]
    Mi = np.linalg.inv(M)
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-Mi @ Q, -Mi @ P]])
    return np.linalg.eigvals(A)


def naive_verdict(s):
    re = np.real(s)
    return "unstable" if np.any(re > 0) else "critical" if np.any(re == 0) else "stable"


# ---------------------------------------------------------------------------------------------
def pendulum_constraint_stiffness():
    model = load_case(case_path("pendulum"))
    eq = equilibrium(model)
    wrong = linearize(model, eq, constraint_stiffness=False)
    right = linearize(model, eq)
    mw = modes(wrong.M, wrong.P, wrong.Q)
    mr = modes(right.M, right.P, right.Q)
    exact = np.sqrt(9.81 / 1.0)
    return FailCase(
        "pendulum: constraint-force stiffness", "linearize without Σλ∇²Φ",
        f"ω = {mw.omega_n[0]:.3g} rad/s ({mw.kind[0]})",
        f"ω = {mr.omega_n[0]:.10g} rad/s ({mr.kind[0]})",
        f"ω = √(g/l) = {exact:.10g} rad/s (closed form)",
        naive_wrong=abs(mw.omega_n[0] - exact) > 0.5 * exact,
        mbseig_right=abs(mr.omega_n[0] - exact) <= 1e-10 * exact,
        data={"omega_naive": float(mw.omega_n[0]), "omega_mbseig": float(mr.omega_n[0]),
              "exact": exact})


def four_bar_constraint_stiffness():
    model = load_case(case_path("four_bar"))
    eq = equilibrium(model)
    wrong = linearize(model, eq, constraint_stiffness=False)
    right = linearize(model, eq)
    ww = modes(wrong.M, wrong.P, wrong.Q).omega_n[0]
    wr = modes(right.M, right.P, right.Q).omega_n[0]
    shift = (ww - wr) / wr
    return FailCase(
        "loaded four-bar: constraint-force stiffness", "linearize without Σλ∇²Φ",
        f"ω = {ww:.6g} rad/s ({100 * shift:+.2f} %)", f"ω = {wr:.6g} rad/s",
        "independent 1-DOF reduction (tests/test_four_bar.py)",
        naive_wrong=abs(shift) > 1e-3, mbseig_right=True,
        data={"omega_naive": float(ww), "omega_mbseig": float(wr), "shift": float(shift)})


def ziegler_matrices(load, c=1.0, length=1.0, m=1.0):
    """Ziegler's double pendulum (masses 2m, m; links of length l; springs c; follower force at
    the tip):

        M = m l² [[3, 1], [1, 1]],   Q = [[2c − F l, F l − c], [−c, c]]   (non-symmetric)

    Flutter for F > F_cr = (7/2 − √2) c/l (Ziegler 1952; Bolotin 1963, Nonconservative Problems).
    """
    M = m * length**2 * np.array([[3.0, 1.0], [1.0, 1.0]])
    Q = np.array([[2 * c - load * length, load * length - c], [-c, c]])
    return M, np.zeros((2, 2)), Q


ZIEGLER_CRITICAL = 3.5 - np.sqrt(2.0)


def ziegler_follower():
    load = 2.2  # c/l; above F_cr = 2.0858
    M, P, Q = ziegler_matrices(load)
    md = modes(M, P, Q)
    w2 = sla.eigh(0.5 * (Q + Q.T), M, eigvals_only=True)  # symmetric part forced into eigh
    naive_kind = "divergence" if np.any(w2 < 0) else "oscillatory"
    below = modes(*ziegler_matrices(1.9))
    return FailCase(
        "Ziegler pendulum, follower load 2.2 c/l", "eigh on the symmetric part of Q",
        f"{naive_kind} (real s), static buckling at F = 2 c/l",
        f"{md.verdict}: {', '.join(sorted(set(md.kind)))}; at F = 1.9 c/l: {below.verdict}",
        f"flutter above F_cr = (7/2 − √2) c/l = {ZIEGLER_CRITICAL:.4f} c/l (Ziegler 1952)",
        naive_wrong=naive_kind != "flutter",
        mbseig_right=("flutter" in md.kind and below.verdict == "critical"),
        data={"kinds": list(md.kind)})


def badly_scaled(n=12, seed=4):
    """Masses 1e-6…1 kg, springs 1e3…1e9 N/m (shuffled), light dashpots.  M, K, C symmetric
    positive definite ⇒ every mode decays (Re s < 0): the energy-dissipation theorem.

    What the unscaled pencil gets wrong is the damping itself: its Re s of some mode is off by
    more than that mode's δ, so the sign its verdict reads is set by rounding (which sign comes
    out depends on the BLAS kernel: unstable on some, stable on others).  That error, not the
    verdict it happens to give, is what ``naive_wrong`` tests: |Re s_naive − Re s| > δ for some
    mode, against mbseig's eigenvalues, whose own bound (tolerance/safety) is far below δ.
    """
    M, C, K = badly_scaled_matrices(n, seed)
    naive = modes(M, C, K, solver="qz", scale=False)  # the unscaled companion pencil
    s_naive = naive.all_eigenvalues
    s_comp = naive_companion(M, C, K)
    md = modes(M, C, K)
    s_ref = md.all_eigenvalues
    pair = np.abs(s_naive[:, None] - s_ref[None, :])  # one naive eigenvalue per reference one
    i, j = linear_sum_assignment(pair)
    off = np.abs(s_naive[i].real - s_ref[j].real) / np.maximum(-s_ref[j].real, np.finfo(float).tiny)
    worst = int(np.argmax(off))
    sn, sr = s_naive[i][worst], s_ref[j][worst]
    return FailCase(
        "badly scaled chain (m 1e-6…1 kg, k 1e3…1e9 N/m, dashpots 1e-9…1e-6 N s/m)",
        "QZ on the unscaled companion pencil + Re s > 0 rule",
        f"{naive_verdict(s_naive)}, but at |s| = {abs(sr):.3g} rad/s Re s = {sn.real:.3g} against "
        f"{sr.real:.3g}: off by {off[worst]:.3g}× its δ, a sign set by rounding; "
        f"explicit M⁻¹ companion (geev balances): {naive_verdict(s_comp)}",
        f"{md.verdict} ({md.solver}; min δ/tol = {np.min(md.delta / md.tolerance):.3g}, "
        f"max η = {md.backward_error.max():.1e})",
        "stable: M, K, C symmetric positive definite (energy dissipation)",
        naive_wrong=bool(off[worst] > 1.0), mbseig_right=md.verdict == "stable",
        data={"max_re_naive": float(s_naive.real.max()), "min_delta": float(md.delta.min()),
              "naive_error_over_delta": float(off[worst]),
              "min_delta_over_tol": float(np.min(md.delta / md.tolerance))})


def badly_scaled_matrices(n=12, seed=4):
    """M, C, K of :func:`badly_scaled`.  Dashpots 1e-7 N s/m, except 1e-6 at the two that damp
    the modes of the heaviest masses (whose normwise bound κη is widest against their δ) and
    1e-9 at the two that damp the mode at |s| ≈ 1.3e5 rad/s (the one whose Re s the unscaled
    pencil misplaces most).  Measured on the five distinct OpenBLAS kernels of an x86-64 build
    (SkylakeX, Haswell, Sandybridge, Nehalem, Katmai), one and two threads: mbseig's δ/tol ≥ 5.6
    on every mode and the naive error 11–15 δ on that one, so neither side rests on one
    kernel's rounding (with dashpots of 1e-7/1e-8 alone both margins were under 2)."""
    rng = np.random.default_rng(seed)
    m = np.logspace(-6, 0, n)
    k = np.logspace(3, 9, n + 1)[rng.permutation(n + 1)]
    c = np.full(n + 1, 1e-7)
    c[[2, 10]], c[[3, 5]] = 1e-6, 1e-9

    def chain(v):
        return np.diag(v[:-1] + v[1:]) - np.diag(v[1:-1], 1) - np.diag(v[1:-1], -1)

    return np.diag(m), chain(c), chain(k)


def large_undamped(n=120):
    k, m = 1000.0, 1.0
    K = 2 * k * np.eye(n) - k * np.eye(n, k=1) - k * np.eye(n, k=-1)
    M = m * np.eye(n)
    s_naive = naive_companion(M, np.zeros((n, n)), K)
    md = modes(M, np.zeros((n, n)), K, solver="companion")
    n_pos = int(np.sum(s_naive.real > 0))
    return FailCase(
        f"undamped chain, n = {n} (general companion path)", "naive companion + Re s > 0 rule",
        f"{naive_verdict(s_naive)} ({n_pos} eigenvalues with Re s > 0, "
        f"max {s_naive.real.max():.2g})",
        f"{md.verdict} (|δ| ≤ tol, largest tol {md.tolerance.max():.2g} rad/s)",
        "critical: undamped, ω_j = 2√(k/m) sin(jπ/(2(n+1))) (closed form)",
        naive_wrong=naive_verdict(s_naive) != "critical", mbseig_right=md.verdict == "critical",
        data={"n_positive": n_pos})


def repeated_and_defective():
    """Isotropic 2-D oscillator (ω double), critically damped SDOF (s = −1 defective),
    free-free chain (rigid mode), massless middle point (singular M)."""
    out = {}
    # repeated: two identical uncoupled oscillators k = 4, m = 1 → ω = 2 twice
    md = modes(np.eye(2), np.zeros((2, 2)), 4 * np.eye(2))
    out["repeated"] = (len(md), list(md.omega_n), md.verdict)
    ok_rep = len(md) == 2 and np.allclose(md.omega_n, 2.0, rtol=1e-12) and md.verdict == "critical"
    # defective: s² + 2s + 1 = 0 → s = −1 (double, one eigenvector)
    md = modes(np.eye(1), 2 * np.eye(1), np.eye(1))
    out["defective"] = (len(md), list(md.eigenvalues), list(md.kind), md.verdict)
    ok_def = (len(md) == 2 and np.allclose(md.eigenvalues, -1.0, atol=1e-7)
              and md.kind == ["overdamped", "overdamped"] and md.verdict == "stable")
    # rigid body: free-free chain of 3 (ω = 0, √(k/m), √(3k/m))
    K = np.array([[1.0, -1, 0], [-1, 2, -1], [0, -1, 1]])
    md = modes(np.eye(3), np.zeros((3, 3)), K)
    s_naive = naive_companion(np.eye(3), np.zeros((3, 3)), K)
    out["rigid"] = (len(md), list(md.kind), naive_verdict(s_naive))
    ok_rig = (len(md) == 3 and md.kind.count("rigid-body") == 1
              and np.allclose(md.omega_n[1:], [1.0, np.sqrt(3.0)], rtol=1e-12))
    # singular mass: wall–m–(massless)–m–wall with springs k: ω² = k/m, 2k/m (static condensation)
    M = np.diag([1.0, 0.0, 1.0])
    K = np.array([[2.0, -1, 0], [-1, 2, -1], [0, -1, 2]])
    md = modes(M, np.zeros((3, 3)), K)
    try:
        naive_companion(M, np.zeros((3, 3)), K)
        naive_singular = "ran"
    except np.linalg.LinAlgError:
        naive_singular = "LinAlgError: singular M"
    out["singular_mass"] = (len(md), list(md.omega_n), md.n_infinite, md.solver)
    ok_sing = len(md) == 2 and np.allclose(md.omega_n, [np.sqrt(1.5 - 0.5), np.sqrt(1.5 + 0.5)],
                                           rtol=1e-10)
    return FailCase(
        "repeated, defective, rigid-body, massless point", "naive companion / counting",
        f"rigid chain: {out['rigid'][2]} (s = 0 split into ±real); massless point: "
        f"{naive_singular}",
        f"ω = 2 twice; s = −1 twice (overdamped, stable); 1 rigid-body + 2 modes; "
        f"massless point: 2 modes, {out['singular_mass'][2]} infinite dropped "
        f"({out['singular_mass'][3]})",
        "closed forms: ω = √(k/m) double; s = −1 double; ω = 0, 1, √3; ω² = k/m, 2k/m",
        naive_wrong=out["rigid"][2] != "critical" or naive_singular != "ran",
        mbseig_right=ok_rep and ok_def and ok_rig and ok_sing, data=out)


def dissipative_integrator(steps_per_period=10, periods=20):
    """Ziegler's pendulum at F = 2.2 c/l has a flutter mode s = σ + iω with σ > 0.  Backward
    Euler with h = T/10 multiplies it by 1/(1 − hs) per step; |1 − hs| > 1 here, so the
    simulated flutter decays: the time domain says stable.  mbseig's time-domain check
    (DOP853, rtol 1e-10, on the nonlinear case) measures the growth."""
    M, P, Q = ziegler_matrices(2.2)
    n = M.shape[0]
    Mi = np.linalg.inv(M)
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-Mi @ Q, -Mi @ P]])
    lam, Vec = np.linalg.eig(A)
    k = int(np.argmax(lam.real))  # the flutter eigenvalue
    s = lam[k]
    h = 2 * np.pi / abs(s.imag) / steps_per_period
    step = np.linalg.inv(np.eye(2 * n) - h * A)
    z = Vec[:, k].real.copy()
    z0 = np.linalg.norm(z)
    for _ in range(steps_per_period * periods):
        z = step @ z
    growth = np.linalg.norm(z) / z0
    naive_delta = np.log(abs(1 - h * s)) / h  # apparent δ of the discrete flutter mode
    model = load_case(case_path("ziegler_pendulum"), config="flutter")
    eq = equilibrium(model)
    lin = linearize(model, eq)
    md = modes(lin.M, lin.P, lin.Q, N=lin.N)
    res = check_modes(model, eq, lin, md)
    flut = [m for m in res.modes if m.predicted_delta < 0 and not m.skipped]
    measured = flut[0].measured_delta if flut else float("nan")
    td = (f"δ measured {measured:+.4g} (predicted {flut[0].predicted_delta:+.4g}): unstable"
          if flut else "no flutter mode checked")
    right = bool(flut) and measured < 0 and flut[0].passed
    return FailCase(
        "time domain: Ziegler pendulum past the flutter load",
        "backward Euler, 10 steps per period",
        f"response ×{growth:.2g} after {periods} periods (apparent δ = {naive_delta:+.3g}): "
        "looks stable",
        f"mbseig check (DOP853, rtol 1e-10): {td}",
        f"flutter, Re s = {s.real:+.4g} (eigenvalue of the linear model)",
        naive_wrong=growth < 1, mbseig_right=right,
        data={"growth": float(growth), "naive_delta": float(naive_delta),
              "measured_delta": float(measured)})


def driven_pendulum_frozen_time():
    """The pendulum on a vertically driven pivot (cases/pendulum_shaken_pivot.toml and
    inverted_pendulum_shaken_pivot.toml): eigenvalues of the linearization frozen at 64
    instants against the Floquet multipliers.  Reference: Mathieu's equation, a = ±4g/(lω²),
    q = 2A/l, characteristic values from scipy.special.mathieu_a / mathieu_b."""
    from scipy.special import mathieu_a, mathieu_b

    from ..casefile import read_case
    from ..studies.periodic import periodic_analysis
    from ..studies.periodic_listing import frozen_summary

    out = {}
    for key, name in (("hanging", "pendulum_shaken_pivot"),
                      ("inverted", "inverted_pendulum_shaken_pivot")):
        a = periodic_analysis(read_case(case_path(name)))
        out[key] = (a, frozen_summary(a))
    (ah, fh), (ai, fi) = out["hanging"], out["inverted"]
    p = ah.parameters
    q = 2 * p["A"] / p["l"]
    a_h = 4 * p["g"] / (p["l"] * p["w"] ** 2)
    in_tongue = mathieu_b(1, q) < a_h < mathieu_a(1, q)
    w_star = np.sqrt(-4 * ai.parameters["g"] / (ai.parameters["l"] * mathieu_a(0, q)))
    held = ai.parameters["w"] > w_star
    rh, ri = ah.floquet, ai.floquet
    return FailCase(
        "driven pendulum: frozen-time eigenvalues", "eigenvalues frozen at 64 instants",
        f"hanging at ω = {p['w']:g}: max Re s = {fh['max_real_part']:.3g} ({fh['verdict']}); "
        f"inverted at ω = {ai.parameters['w']:g}: max Re s = {fi['max_real_part']:.3g} "
        f"({fi['verdict']})",
        f"Floquet: hanging |μ| = {rh.spectral_radius:.6g} ± {rh.error_bound:.1e} ({rh.verdict}); "
        f"inverted |μ| = {ri.spectral_radius:.10g} ± {ri.error_bound:.1e} ({ri.verdict})",
        f"Mathieu (scipy mathieu_a/b): hanging a = {a_h:.4g} inside the principal tongue "
        f"({mathieu_b(1, q):.4g}, {mathieu_a(1, q):.4g}): unstable; inverted held above "
        f"ω* = {w_star:.8g} rad/s",
        naive_wrong=fh["verdict"] != "unstable" and fi["verdict"] == "unstable",
        mbseig_right=(in_tongue and rh.verdict == "unstable" and held
                      and ri.verdict != "unstable"),
        data={"frozen_hanging": fh["max_real_part"], "frozen_inverted": fi["max_real_part"],
              "mu_hanging": rh.spectral_radius, "mu_inverted": ri.spectral_radius,
              "bound_hanging": rh.error_bound, "bound_inverted": ri.error_bound})


def rolling_disk_naive():
    """The rolling disk at its critical speed linearized without the velocity constraints'
    position derivative (:mod:`mbseig.bench.failcases_steady`)."""
    from .failcases_steady import rolling_disk_naive as case

    return case()


ALL = [pendulum_constraint_stiffness, four_bar_constraint_stiffness, ziegler_follower,
       badly_scaled, large_undamped, repeated_and_defective, dissipative_integrator,
       driven_pendulum_frozen_time, rolling_disk_naive]


def run_all():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        return [f() for f in ALL]
