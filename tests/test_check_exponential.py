"""The exponential Adams integrator of the time-domain check (mbseig.check.exponential): its φ
functions, its order, that it integrates y′ = f whatever J it starts from, and that it refuses
a J it cannot diagonalize."""

import math
import warnings

import numpy as np
import pytest
from scipy.integrate import IntegrationWarning, quad, solve_ivp
from scipy.linalg import expm

from mbseig.check.exponential import (
    ORDER,
    ExponentialAdams,
    ExponentialUnusable,
    phi_functions,
)

W_SLOW, W_FAST = 1.0, 1e2  # a slow mode and a stiff one (h ω = 30 at the steps taken)
A0 = 0.1


def f(t, y):
    """A Duffing oscillator (cubic spring, light damping) coupled quadratically to a damped
    stiff mode: the shape of a flexible model's remainder (slow mode excited, stiff mode
    driven at second order)."""
    x1, x2, v1, v2 = y
    return np.array([v1, v2, -W_SLOW**2 * x1 - 0.3 * x1**3 - 0.1 * x1 * x2 - 0.02 * v1,
                     -W_FAST**2 * x2 - 0.05 * x1**2 - 10.0 * v2])


def jacobian(k_slow=W_SLOW**2):
    return np.array([[0.0, 0, 1, 0], [0, 0, 0, 1], [-k_slow, 0, -0.02, 0],
                     [0, -W_FAST**2, 0, -10.0]])


UNITS = np.array([1.0, 1.0, W_SLOW, W_FAST])  # velocities in units of their mode's ω
Y0 = np.array([A0, 0.0, 0.0, 0.0])


@pytest.fixture(scope="module")
def reference():
    """The same system by DOP853 at rtol 1e-12, atol 1e-15 (an independent method: it agrees
    with itself at rtol 1e-13 to 3e-16 and with Radau at rtol 1e-10 to 2e-12)."""
    t = np.linspace(0.0, 20 * 2 * np.pi, 801)
    sol = solve_ivp(f, (0, t[-1]), Y0, method="DOP853", t_eval=t, rtol=1e-12, atol=1e-15)
    assert sol.success
    return t, sol.y


@pytest.mark.parametrize("x", [0.5 + 0.3j, 1.9j, 2.1, -3.0 + 1.0j, 40j, -30.0, 1e-9])
def test_phi_functions_equal_their_integral(x):
    """φ_k(x) = ∫₀¹ e^{(1−u)x} u^{k−1}/(k−1)! du (k ≥ 1), φ_0 = e^x, on both branches (series
    below |x| = 2, recurrence above); reference: scipy's adaptive quadrature of the integral, its
    oscillation e^{−i Im(x) u} as the weight of QUADPACK's QAWO
    (epsrel 1e-12, met without warning), agreement 2e-12 relative: the quadrature's error is
    below 1e-12 and the recurrence's grows at most as (k+1)!/2^k ε ≈ 80 ε at k = 6."""
    P = phi_functions(np.array([x]), 6)[:, 0]
    assert abs(P[0] - np.exp(x)) <= 1e-15 * abs(np.exp(x))
    with warnings.catch_warnings():
        warnings.simplefilter("error", IntegrationWarning)  # a quad short of 1e-12 fails here
        a, b = x.real, x.imag
        for k in range(1, 7):
            # e^{(1−u)x} = e^x e^{−au} (cos bu − i sin bu): the oscillation as quad's weight (QAWO)
            def smooth(u, k=k):
                return np.exp(-a * u) * u ** (k - 1) / math.factorial(k - 1)
            if b:
                re = quad(smooth, 0, 1, weight="cos", wvar=b, epsabs=0, epsrel=1e-12, limit=400)[0]
                im = -quad(smooth, 0, 1, weight="sin", wvar=b, epsabs=0, epsrel=1e-12, limit=400)[0]
            else:
                re, im = quad(smooth, 0, 1, epsabs=0, epsrel=1e-12, limit=400)[0], 0.0
            ref = np.exp(x) * (re + 1j * im)
            assert abs(P[k] - ref) <= 2e-12 * abs(ref), (k, P[k], ref)


def test_order_at_fixed_steps(reference):
    """At a fixed step (no control) the error at the end of 20 periods falls as h^ORDER (6: the
    order of predictor and corrector): halving h from T/16 to T/32 and to T/64 divides it by
    2^6 = 64 within a factor 2 (measured ratios 98 and 50)."""
    t, Y = reference
    errs = []
    for per_period in (16, 32, 64):
        h = 2 * np.pi / per_period
        ea = ExponentialAdams(f, jacobian(), rtol=1.0, atol=np.ones(4), scale=UNITS)
        out = ea.run(Y0, t, h, fixed_step=True)
        errs.append(np.max(np.abs(out[0] - Y[0])))
    assert ORDER == 6
    for a, b in zip(errs, errs[1:], strict=False):
        assert 2.0 ** ORDER / 2 <= a / b <= 2.0 ** ORDER * 2, errs


@pytest.mark.parametrize("k_slow", [W_SLOW**2, 1.02 * W_SLOW**2])
def test_solves_f_whatever_j_it_starts_from(reference, k_slow):
    """With the exact J and with a J whose slow stiffness is 2 % high (its own ω 1 % off: over
    20 periods its linear solution drifts 1.1 rad out of phase, more than 0.2 of the initial
    amplitude away), the run at rtol 1e-8 stays within
    1e-5 of the amplitude of the reference (the local error per step is controlled to 1e-8 of
    the state; over ~1e3 steps it adds up to at most 1e-5).  A wrong J costs steps, not
    accuracy."""
    t, Y = reference
    ea = ExponentialAdams(f, jacobian(k_slow), rtol=1e-8, atol=np.full(4, 1e-9),
                          scale=UNITS)
    out = ea.run(Y0, t, 2 * (t[1] - t[0]))
    assert np.max(np.abs(out[0] - Y[0])) <= 1e-5 * A0
    if k_slow != W_SLOW**2:  # the wrong J alone would be far off
        lin = np.array([expm(jacobian(k_slow) * s) @ Y0 for s in t[::8]])
        assert np.max(np.abs(lin[:, 0] - Y[0, ::8])) > 0.2 * A0


def test_fewer_evaluations_than_radau(reference):
    """On this stiff system at rtol 1e-6 the exponential run needs fewer right-hand sides than
    Radau at the same tolerances (measured: 554 against 6,259) and is as accurate to
    within the tolerance (both within 1e-4 of the amplitude: 100 rtol over 800 samples)."""
    t, Y = reference
    atol = np.full(4, 1e-7)
    ea = ExponentialAdams(f, jacobian(), rtol=1e-6, atol=atol, scale=UNITS)
    out = ea.run(Y0, t, 2 * (t[1] - t[0]))
    rad = solve_ivp(f, (0, t[-1]), Y0, method="Radau", t_eval=t, rtol=1e-6, atol=atol,
                    jac=jacobian())
    assert np.max(np.abs(out[0] - Y[0])) <= 1e-4 * A0
    assert np.max(np.abs(rad.y[0] - Y[0])) <= 1e-4 * A0
    assert ea.nfev < rad.nfev


def test_a_defective_j_is_refused():
    """A Jordan block (a free body: x″ = 0) has no eigenvector basis: refused, so the check
    falls back to Radau and says why."""
    J = np.array([[0.0, 1.0], [0.0, 0.0]])
    with pytest.raises(ExponentialUnusable, match="nearly defective"):
        ExponentialAdams(lambda t, y: J @ y, J, rtol=1e-6, atol=np.ones(2))



def test_a_run_over_its_budget_gives_way(reference):
    """More right-hand sides a sample than the budget (the remainder varying faster than the
    sampling: fast modes ringing into the checked one) stops the run with ExponentialUnusable,
    which the check answers with Radau (next test)."""
    t, _ = reference
    ea = ExponentialAdams(f, jacobian(), rtol=1e-10, atol=np.full(4, 1e-12), scale=UNITS)
    with pytest.raises(ExponentialUnusable, match="faster than the sampling"):
        ea.run(Y0, t, 2 * (t[1] - t[0]), budget=0.05)


def test_check_falls_back_to_radau_and_says_why(monkeypatch):
    """The 2-element oblique cantilever's mode 1 with a budget no run can keep: the check runs
    Radau, passes (ω within 1e-5 of the prediction, as with either integrator in
    tests/test_check_beams3d.py) and its integrator names the reason."""
    from conftest import CASES

    import mbseig.check.tangent as tangent
    from mbseig.check.modes import check_modes
    from mbseig.studies import analyze

    monkeypatch.setattr(tangent, "EXPONENTIAL_BUDGET", 1e-3)
    a = analyze(CASES / "cantilever_3d_oblique.toml", params={"n": 2})
    res = check_modes(a.model, a.eq, a.linear, a.modes, indices=[1], periods=1.0,
                      ode_rtol=1e-4)
    m = res.modes[0]
    assert res.passed and res.integrator.startswith("Radau (the exponential integrator does "
                                                    "not apply: the remainder varies faster")
    assert abs(m.measured_omega / m.predicted_omega - 1) < 1e-5
