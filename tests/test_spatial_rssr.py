"""Spatial RSSR four-bar with preload (cases/rssr_four_bar.toml) against an independent 1-DOF
reduction written here, and the error made without the constraint-force stiffness Σλ∇²Φ.

Reference (independent of mbseig's natural coordinates): the crank angle φ about z is the
coordinate; the rocker angle ψ(φ) about x solves the loop closure F = |B(ψ) − A(φ)|² − L² = 0,
with ψ', ψ'' by implicit differentiation; the potential V(φ) (two torsional springs and gravity)
and the kinetic energy ½ m(φ) φ̇² (crank and rocker about their axes, the coupler from its end
velocities: v_G = (v_A + v_B)/2, ω⊥ = e × (v_B − v_A)/L; its spin about A–B is decoupled)
give the equilibrium V'(φ₀) = 0 (Newton to machine precision) and ω² = V''(φ₀)/m(φ₀).
Tolerance: 1e-9 relative (both sides converge to ~1e-14).
"""

import math
from pathlib import Path

import numpy as np
import pytest

import mbseig

CASE = Path(__file__).resolve().parent.parent / "cases" / "rssr_four_bar.toml"


def reduction(p):
    """(φ₀, ω) of the 1-DOF reduction for the case's parameters p."""
    r1, r2, L = p["r1"], p["r2"], p["L"]
    C = np.array([p["Cx"], p["Cy"], p["Cz"]])
    g = p["g"]

    def A(f):
        return r1 * np.array([math.cos(f), math.sin(f), 0.0])

    def B(s):
        return C + r2 * np.array([0.0, -math.sin(s), math.cos(s)])

    def dA(f, k):  # k-th derivative of A
        return r1 * np.array([math.cos(f + k * math.pi / 2), math.sin(f + k * math.pi / 2), 0.0])

    def dB(s, k):
        return r2 * np.array([0.0, -math.sin(s + k * math.pi / 2), math.cos(s + k * math.pi / 2)])

    def psi_of(f, s):
        for _ in range(60):  # Newton on the loop closure, from the previous ψ
            d = B(s) - A(f)
            F, Fs = d @ d - L * L, 2 * d @ dB(s, 1)
            s -= F / Fs
            if abs(F) < 1e-16:
                break
        d = B(s) - A(f)
        Ff, Fs = -2 * d @ dA(f, 1), 2 * d @ dB(s, 1)
        Fff = 2 * dA(f, 1) @ dA(f, 1) - 2 * d @ dA(f, 2)
        Fss = 2 * dB(s, 1) @ dB(s, 1) + 2 * d @ dB(s, 2)
        Ffs = -2 * dA(f, 1) @ dB(s, 1)
        s1 = -Ff / Fs
        s2 = -(Fff + 2 * Ffs * s1 + Fss * s1 * s1) / Fs
        return s, s1, s2

    w = g * (r2 / 2) * (p["m2"] + p["m3"])  # gravity: V_g = w cos ψ (+ const)

    def dV(f, s):
        s, s1, s2 = psi_of(f, s)
        V1 = p["kA"] * (f - p["alphaA"]) + p["kB"] * (s - p["alphaB"]) * s1 - w * math.sin(s) * s1
        V2 = (p["kA"] + p["kB"] * (s1 * s1 + (s - p["alphaB"]) * s2)
              - w * (math.cos(s) * s1 * s1 + math.sin(s) * s2))
        return s, s1, V1, V2

    f, s = 0.0, 0.0
    for _ in range(60):
        s, s1, V1, V2 = dV(f, s)
        f -= V1 / V2
        if abs(V1) < 1e-15 * p["kA"]:
            break
    s, s1, V1, V2 = dV(f, s)
    vA = np.cross([0.0, 0.0, 1.0], A(f))
    vB = s1 * np.cross([1.0, 0.0, 0.0], B(s) - C)
    e = (B(s) - A(f)) / L
    vG, wp = (vA + vB) / 2, np.cross(e, vB - vA) / L
    m = ((p["J1"] + p["m1"] * r1 * r1 / 4) + (p["J3"] + p["m3"] * r2 * r2 / 4) * s1 * s1
         + p["m2"] * vG @ vG + p["J2"] * wp @ wp)
    return f, math.sqrt(V2 / m)


@pytest.fixture(scope="module")
def solved():
    model = mbseig.load_case(CASE)
    eq = mbseig.equilibrium(model)
    return model, eq


def test_rssr_frequency_against_reduction(solved):
    model, eq = solved
    phi0, omega = reduction(model.parameters)
    md = mbseig.modes(mbseig.linearize(model, eq))
    assert md.kind == ["rigid-body", "oscillatory"]  # the coupler's spin, the mechanism
    assert md.omega_n[1] == pytest.approx(omega, rel=1e-9)
    # the equilibrium posture: the crank's angle from the reference
    crank = model.constraints[0]  # the crank bearing
    assert crank.name.endswith("'crank bearing'")
    u = eq.q[[model.coordinate_names.index(f"crank.u.{a}") for a in "xy"]]
    assert math.atan2(u[1], u[0]) == pytest.approx(phi0, abs=1e-10)


def test_rssr_error_without_constraint_stiffness(solved):
    """Without Σλ∇²Φ the mechanism frequency is off by 10 % (the common omission)."""
    model, eq = solved
    _, omega = reduction(model.parameters)
    wrong = mbseig.modes(mbseig.linearize(model, eq, constraint_stiffness=False)).omega_n[1]
    err = abs(wrong - omega) / omega
    assert 0.05 < err < 0.2, err


def test_rssr_time_domain_check_passes_and_fails_without_constraint_stiffness(solved):
    """The nonlinear 3-D model confirms the correct linearization and rejects the one
    without Σλ∇²Φ (its frequency is measured 10 % away from the prediction)."""
    model, eq = solved
    lin = mbseig.linearize(model, eq)
    md = mbseig.modes(lin)
    good = mbseig.check_modes(model, eq, lin, md, indices=[2], periods=5)
    assert good.passed and good.modes[0].rel_error_omega < 1e-6
    lin_bad = mbseig.linearize(model, eq, constraint_stiffness=False)
    bad = mbseig.check_modes(model, eq, lin_bad, mbseig.modes(lin_bad), indices=[2], periods=5)
    assert not bad.passed and bad.modes[0].rel_error_omega > 0.05


def test_coupler_spin_is_rigid_body_and_no_spurious_bifurcation():
    """The coupler between two ball joints spins freely about A–B (zero stiffness: the
    reduction in the module docstring decouples it).  Its eigenvalue comes out of rounding
    (|s| ~ 3e-5 at kA = 30.1, a real ± pair in the old SVD basis); it must be a rigid-body mode
    (critical), never a divergence, and a sweep across kA must report no branch point from the
    noise sign of that zero pivot (before the numerically-singular rule, kA = 20…31 in 3 points
    reported one at 22.01)."""
    spec = mbseig.read_case(CASE)
    for k in (25.0, 30.1):
        md = mbseig.analyze(spec, params={"kA": k}).modes
        spin = int(np.argmin(np.abs(md.eigenvalues)))
        assert md.kind[spin] == "rigid-body" and md.stability[spin] == "critical"
        assert md.verdict == "critical"
        # the oscillatory mode is the 1-DOF reduction's (1e-9 relative, module docstring)
        p = dict(spec.build(kA=k).parameters)
        omega = reduction(p)[1]
        other = [s for i, s in enumerate(md.eigenvalues) if i != spin]
        assert abs(abs(other[0]) - omega) <= 1e-9 * omega
    res = mbseig.run_sweep(spec, [("kA", np.linspace(20.0, 31.0, 3))], jobs=1)
    assert [b for b in res.boundaries if b.get("event") == "branch point"] == []
    assert res.boundaries == []
