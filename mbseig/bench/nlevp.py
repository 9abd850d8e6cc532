"""Quadratic eigenproblems of the NLEVP collection, built from their published definitions, and
the bench section that solves each with its backward error and verdict.

Source: T. Betcke, N. J. Higham, V. Mehrmann, C. Schröder and F. Tisseur, NLEVP: a collection of
nonlinear eigenvalue problems, ACM TOMS 39(2), 2013 (MATLAB toolbox, version 4.1).  NLEVP writes
Q(λ) = λ²A₂ + λA₁ + A₀; here M = A₂, P = A₁, Q = A₀.  Each function returns (M, P, Q) and a dict
with the reference (exact eigenvalues where the collection gives them, else what decides the
verdict) so that the tests (tests/test_eigen_trust.py) and the bench use one definition.
"""

from __future__ import annotations

import math
import time
import warnings

import numpy as np

from ..errors import MbseigError
from ..modal import modes

__all__ = ["qep1", "qep2", "qep3", "power_plant", "bicycle", "rotating_mass", "PROBLEMS",
           "bench_nlevp"]


def qep1():
    """qep1 (Tisseur & Meerbergen 2001, p. 250): eigenvalues 1/3, 1/2, 1, ±i, ∞ (M singular)."""
    M = np.array([[0.0, 6, 0], [0, 6, 0], [0, 0, 1]])
    P = np.array([[1.0, -6, 0], [2, -7, 0], [0, 0, 0]])
    Q = np.eye(3)
    return M, P, Q, {"eigenvalues": [1 / 3, 1 / 2, 1.0, 1j, -1j], "n_infinite": 1,
                     "verdict": "unstable", "source": "NLEVP qep1: exact eigenvalues"}


def qep2(q_scale=1.0):
    """qep2 (Tisseur & Meerbergen 2001, p. 256): A₂ = I, A₁ = [[−2, 0, 1], 0, 0], A₀ =
    diag(1, −1, 1); det Q(s) = (s − 1)³(s + 1)(s² + 1): a defective triple root at s = +1.
    ``q_scale`` multiplies A₀ (the issue's Q = diag(1e300, −1e300, 1e300)): then the roots are
    s = ±√q (the x₂ row: a divergence at +√q), ±i√q, 1 ± i√(q − 1)."""
    M = np.eye(3)
    P = np.array([[-2.0, 0, 1], [0, 0, 0], [0, 0, 0]])
    Q = np.diag([1.0, -1.0, 1.0]) * q_scale
    if q_scale == 1.0:
        ev = [1.0, 1.0, 1.0, -1.0, 1j, -1j]
    else:
        r = math.sqrt(q_scale)
        ev = [r, -r, 1j * r, -1j * r, complex(1, math.sqrt(q_scale - 1)),
              complex(1, -math.sqrt(q_scale - 1))]
    return M, P, Q, {"eigenvalues": ev, "n_infinite": 0, "verdict": "unstable",
                     "source": "NLEVP qep2: det Q(s) = (s − 1)³(s + 1)(s² + 1)"}


def qep3(e=None):
    """qep3 (Dedieu & Tisseur 2003, p. 89), E = −1 + √(ε/2): eigenvalues 0, 1, 1 + E
    (= 1.05e-8), 2, 3, ∞ (the collection lists the coefficients in reverse order)."""
    e = -1 + math.sqrt(np.finfo(float).eps / 2) if e is None else e
    M = np.array([[1.0, -1, -1], [0, 1, 0], [0, 0, 0]])
    P = np.array([[-3.0, 1, 0], [0, -1 - e, 0], [0, 0, 1]])
    Q = np.array([[2.0, 0, 9], [0, 0, 0], [0, 0, -3]])
    return M, P, Q, {"eigenvalues": [0.0, 1.0, 1 + e, 2.0, 3.0], "n_infinite": 1,
                     "verdict": "unstable", "source": "NLEVP qep3: exact eigenvalues"}


def power_plant(mu=0.2):
    """power_plant (Itoh 1973; Tisseur & Meerbergen 2001): 8 DOF, M, D real symmetric, K =
    (1 + iμ)K₀ complex (hysteretic damping).  No closed form: the reference is a 50-digit
    solve (tests); 4 eigenvalues have Re s > 0 (unstable) at μ = 0.2."""
    M = np.diag([0.54e1, 0.168e7, 0.552e2, 0.8711e8, 0.578e2, 0.235e9, 0.16e2, 0.214e8])
    D = np.zeros((8, 8))
    D[0, 1], D[0, 2], D[0, 3] = -0.7492e4, -0.999e1, 0.979e4
    D[1, 2], D[1, 3] = 0.7492e4, -0.1221e8
    D[2, 3], D[2, 4], D[2, 5] = -0.9674e6, -0.538e3, -0.538e6
    D[3, 4], D[3, 5] = 0.9576e6, -0.1652e10
    D[4, 5], D[4, 6], D[4, 7] = -0.5042e7, -0.3e2, 0.57e5
    D[5, 6], D[5, 7] = -0.3e5, -0.182e9
    D[6, 7] = -0.57e5
    D = D + D.T + np.diag([0.999e1, 0.1045e8, 0.548e3, 0.4329e10, 0.6178e4, 0.4343e11, 0.3e2,
                           0.3473e9])
    K = np.zeros((8, 8))
    K[0, 1], K[0, 2], K[0, 3] = -0.87e7, -0.116e5, 0.1137e8
    K[1, 2], K[1, 3] = 0.87e7, -0.1723e11
    K[2, 3], K[2, 4], K[2, 5] = -0.9334e9, -0.518e6, -0.518e9
    K[3, 4], K[3, 5] = 0.922e9, -0.6878e13
    K[4, 5], K[4, 6], K[4, 7] = 0.3633e9, -0.617e4, 0.1172e8
    K[5, 6], K[5, 7] = -0.617e7, -0.2553e12
    K[6, 7] = -0.1172e8
    K = K + K.T + np.diag([0.116e5, 0.1522e11, 0.5296e6, 0.9461e13, 0.6862e6, 0.9953e13,
                           0.6170e4, 0.2893e12])
    return M, D, (1 + 1j * mu) * K, {"n_unstable": 4, "n_infinite": 0, "verdict": "unstable",
                                     "source": "NLEVP power_plant; 50-digit reference (tests)"}


def bicycle(v=5.0, g=9.81):
    """bicycle (Meijaard, Papadopoulos, Ruina & Schwab 2007, the Whipple benchmark):
    s²M + s v C₁ + g K₀ + v² K₂; self-stable between the weave speed ≈ 4.29 m/s and the capsize
    speed ≈ 6.02 m/s."""
    M = np.array([[80.81722, 2.31941332208709], [2.31941332208709, 0.29784188199686]])
    K0 = np.array([[-80.95, -2.59951685249872], [-2.59951685249872, -0.80329488458618]])
    K2 = np.array([[0.0, 76.59734589573222], [0.0, 2.65431523794604]])
    C1 = np.array([[0.0, 33.86641391492494], [-0.85035641456978, 1.68540397397560]])
    stable = 4.292 < v < 6.024
    return M, v * C1, g * K0 + v * v * K2, {
        "verdict": "stable" if stable else "unstable", "n_infinite": 0,
        "source": "Meijaard et al. 2007: weave speed 4.292 m/s, capsize speed 6.024 m/s"}


def rotating_mass(omega0=2.0, Omega=3.0, q=None, p_entry=None):
    """The bundled rotating_mass case (cases/rotating_mass.toml): s = ±i|ω₀ − Ω|, ±i(ω₀ + Ω);
    ``q`` replaces Q by q·I (the issue's q = −1e300: s ≈ ±√|q| − iΩ, a divergence), ``p_entry``
    = ((i, j), value) sets one entry of P (the issue's 1e300)."""
    M = np.eye(2)
    P = 2 * Omega * np.array([[0.0, -1.0], [1.0, 0.0]])
    Q = (omega0**2 - Omega**2) * np.eye(2) if q is None else q * np.eye(2)
    if p_entry is not None:
        P[p_entry[0]] = p_entry[1]
    verdict = "critical" if q is None and p_entry is None else "unstable"
    return M, P, Q, {"verdict": verdict, "n_infinite": 0,
                     "source": "closed form (cases/rotating_mass.toml)"}


PROBLEMS = {
    "qep1": qep1, "qep2": qep2, "qep3": qep3, "power_plant": power_plant,
    "bicycle v=2 (below weave)": lambda: bicycle(2.0),
    "bicycle v=5 (self-stable)": lambda: bicycle(5.0),
    "qep2, Q × 1e300": lambda: qep2(1e300),
    "rotating mass, Q = −1e300 I": lambda: rotating_mass(q=-1e300),
    "rotating mass, P₀₀ = 1e300": lambda: rotating_mass(p_entry=((0, 0), 1e300)),
}


def bench_nlevp(log=print):
    """Solve every problem of :data:`PROBLEMS` with ``mbseig.modes``: verdict, solver, largest
    backward error, listed modes, time; or the one-line refusal."""
    rows = []
    for name, make in PROBLEMS.items():
        M, P, Q, ref = make()
        t0 = time.perf_counter()
        row = {"section": "nlevp", "method": name, "n": M.shape[0], "reference": ref["source"],
               "expected": ref["verdict"]}
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", RuntimeWarning)  # η above eta_warn: in the row
                md = modes(M, P, Q)
            row.update(verdict=str(md.verdict.word), solver=md.solver, n_listed=len(md),
                       n_infinite=md.n_infinite, eta=float(np.max(md.backward_error, initial=0.0)),
                       refused=None)
        except MbseigError as exc:
            row.update(verdict="refused", solver="–", n_listed=0, n_infinite=0, eta=math.nan,
                       refused=exc.one_line())
        row["time"] = time.perf_counter() - t0
        row["error"] = math.nan
        rows.append(row)
        log(f"nlevp {name:32s} {row['verdict']:9s} (expected {row['expected']}) η {row['eta']:.1e}")
    return rows
