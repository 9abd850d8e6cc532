"""The fast paths of the Floquet analysis give what the direct evaluation gives.

Each fast path is checked against an independent evaluation of the same quantity:
- the Chebyshev interpolants of A(t) against A(t) itself (the projected system evaluated at the
  instant), and the monodromy integrated on them against the monodromy integrated on A(t)
  (scipy solve_ivp DOP853 at rtol 1e-12 both: the difference is the interpolation's);
- the coefficient matrices on their nonzero pattern against the dense trigonometric series of the
  same samples (the same interpolant: rounding only);
- the null-space path with a sparse Φ_q against the same path with the dense Φ_q;
- the rheonomic terms Φ_t, Φ_tt (five-point differences along the Taylor curve of every
  constraint at once) against central differences of Φ of the model at neighbouring instants;
- a chain of pendulums on shaken pivots (benchmarks/periodic_scaling.py, 6 pendulums): its
  dominant multiplier against the single pendulum's Mathieu equation integrated on its own.
"""

import importlib.util
import math
from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp
from conftest import CASES

from mbseig.casefile import read_case
from mbseig.model.timed import TrigSeries
from mbseig.studies.floquet import monodromy
from mbseig.studies.floquet_chebyshev import chebyshev_system
from mbseig.studies.floquet_paths import null_space_path
from mbseig.studies.floquet_sparse import pattern_series
from mbseig.studies.periodic import periodic_analysis, periodic_linearization

PENDULUM = CASES / "pendulum_shaken_pivot.toml"
COLUMN = CASES / "column_pulsating_load.toml"


def _chain_case(n):
    spec = importlib.util.spec_from_file_location(
        "periodic_scaling", Path(__file__).resolve().parents[1] / "benchmarks" /
        "periodic_scaling.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module.CASE.replace("\nn = 6 ", f"\nn = {n} ", 1), module  # the bundled chain


@pytest.fixture
def chain_file(tmp_path):
    text, module = _chain_case(6)
    path = tmp_path / "chain6.toml"
    path.write_text(text)
    return path, module


@pytest.mark.parametrize("case", [PENDULUM, COLUMN])
def test_interpolants_reproduce_the_projected_system(case):
    """At instants off the Chebyshev points, each segment's interpolant equals the projected
    A(t) to 1e-12 of its largest entry (the interpolation keeps coefficients down to 1e-14)."""
    system = periodic_linearization(read_case(case)).system.system
    cheb, record = chebyshev_system(system)
    assert record["evaluations"] >= 13 * len(system.segments)
    for (t0, t1, A), (_, _, C) in zip(system.segments, cheb.segments, strict=True):
        for frac in (0.013, 0.37, 0.71, 0.994):
            t = t0 + frac * (t1 - t0)
            exact = A(t)
            assert np.max(np.abs(C(t) - exact)) <= 1e-12 * np.max(np.abs(exact))


def test_monodromy_on_interpolants_equals_monodromy_on_the_system():
    """DOP853 at rtol 1e-12 on the interpolants and on A(t) itself (the shaken pendulum): the
    two Φ agree to 1e-11 relative (both integrations' tolerance; the interpolation error is far
    below)."""
    system = periodic_linearization(read_case(PENDULUM)).system.system
    exact = monodromy(system, rtol=1e-12)
    fast = monodromy(chebyshev_system(system)[0], rtol=1e-12)
    assert np.linalg.norm(fast - exact) <= 1e-11 * np.linalg.norm(exact)


def test_pattern_series_equals_the_dense_series():
    """A sparse matrix sampled at 16 instants (some entries constant, some moving): the series
    on its pattern equals the dense series of the same samples, value and two derivatives, to
    1e-12; an all-zero matrix is None, a dense one stays dense."""
    rng = np.random.default_rng(3)
    T, N, n = 1.7, 16, 30
    times = np.arange(N) * T / N
    rows, cols = rng.integers(0, n, 40), rng.integers(0, n, 40)
    base = np.zeros((n, n))
    base[rows, cols] = rng.standard_normal(40)
    moving = np.zeros((n, n))
    moving[rows[:10], cols[:10]] = 1.0
    samples = np.array([base + moving * (np.cos(2 * math.pi * t / T) + 0.3 * np.sin(
        6 * math.pi * t / T)) for t in times])
    sparse, dense = pattern_series(samples, T), TrigSeries.fit(samples, T)
    for order in (0, 1, 2):
        for t in (0.1, 0.77, 1.6):
            got = sparse(t, order)
            assert sp.issparse(got)
            want = dense(t, order)
            assert np.max(np.abs(got.toarray() - want)) <= 1e-12 * max(1.0, np.abs(want).max())
    assert pattern_series(np.zeros((N, 4, 4)), T)(0.3) is None
    full = pattern_series(rng.standard_normal((N, 4, 4)), T)
    assert isinstance(full(0.3), np.ndarray)


def test_sparse_constraint_jacobian_gives_the_dense_null_space_path(chain_file):
    """N(t) and Ṅ(t) of the pendulum chain's null-space path from a CSR Φ_q equal those from the
    same Φ_q dense, to 1e-12."""
    lin = periodic_linearization(read_case(chain_file[0]))
    path = lin.system.path
    J = path.phi_q
    dense = null_space_path(lambda t: J(t).toarray(), lambda t: J(t, 1).toarray(),
                            lin.timed.period, start=path.bases[0])
    assert sp.issparse(J(0.1))
    for t in (0.05, 0.4, 0.93 * lin.timed.period):
        for a, b in zip(path.derivative(t), dense.derivative(t), strict=True):
            assert np.max(np.abs(a - b)) <= 1e-12 * max(1.0, np.abs(b).max())


def test_rheonomic_terms_against_differences_of_the_model_in_time():
    """Φ_t and Φ_tt of the shaken pendulum's moving pivot at (q, t) against fourth-order central
    differences of Φ(q, t ± δ), δ = 1e-3 T (truncation ≈ δ⁴ Φ⁽⁵⁾, below 1e-7 here)."""
    lin = periodic_linearization(read_case(PENDULUM))
    timed = lin.timed
    T = timed.period
    q = timed.base.q_init + 0.01
    for t in (0.1 * T, 0.55 * T):
        _, dt, dtt = timed.phi_time(q, t)
        d = 1e-3 * T
        f = [timed.at(t + j * d).phi(q) for j in (-2, -1, 0, 1, 2)]
        fd1 = (f[0] - 8 * f[1] + 8 * f[3] - f[4]) / (12 * d)
        fd2 = (-f[0] + 16 * f[1] - 30 * f[2] + 16 * f[3] - f[4]) / (12 * d * d)
        assert np.max(np.abs(dt - fd1)) <= 1e-7 * max(1.0, np.abs(fd1).max())
        assert np.max(np.abs(dtt - fd2)) <= 1e-5 * max(1.0, np.abs(fd2).max())


def test_chain_dominant_multiplier_is_the_single_pendulum(chain_file):
    """The 6-pendulum chain's modes decouple into Mathieu equations and its mode 0 is the single
    pendulum (benchmarks/periodic_scaling.py): its dominant multiplier equals the single
    pendulum's, integrated on its own (solve_ivp DOP853, rtol 1e-12), within its error bound
    plus 1e-11; 2·6 multipliers."""
    path, module = chain_file
    a = periodic_analysis(read_case(path))
    ref = module.single_pendulum_multiplier()
    mu = a.floquet.multipliers
    assert mu.size == 12
    assert abs(mu[0] - ref) <= a.floquet.error_bounds[0] + 1e-11
    assert a.floquet.verdict == "unstable"
