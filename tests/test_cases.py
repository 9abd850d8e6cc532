"""Every bundled case against the expected values it states (closed forms named in the file).

Tolerances are the case's own ``rtol`` (1e-10 for the closed-form cases) and ``atol`` (only for a
rigid-body mode, whose computed |s| is a rounding residue of order sqrt(eps) * omega_max).
"""

import tomllib

import numpy as np
import pytest
from conftest import CASES
from expected import expected_eigenvalues, expected_omega_n

import mbseig
from mbseig.casefile import motion_kind
from mbseig.studies import analyze

# cases at rest; a case with [motion] (a steady or periodic motion, DESIGN §8) is analysed about
# its motion, not a static equilibrium: tests/test_steady_cases.py and the periodic tests
# check those against their own expected values
CASE_FILES = [p for p in sorted(CASES.glob("*.toml"))
              if motion_kind(tomllib.loads(p.read_text())) is None]


@pytest.mark.parametrize("path", CASE_FILES, ids=lambda p: p.stem)
def test_case_expected_values(path):
    a = analyze(path)
    exp = a.model.expected
    assert exp.get("source"), f"{path.name} must state the source of its expected values"
    params = a.model.parameters
    rtol, atol = exp.get("rtol", 1e-10), exp.get("atol", 0.0)
    w = expected_omega_n(exp, params)
    if w is not None:
        got = np.sort(a.modes.omega_n)
        if exp.get("lowest", False):  # a discretized continuum: only its lowest modes are known
            assert got.size >= w.size
            got = got[:w.size]
        np.testing.assert_allclose(got, np.sort(w), rtol=rtol, atol=atol)
    s = expected_eigenvalues(exp, params)
    if s is not None:
        got = a.modes.eigenvalues
        np.testing.assert_allclose(got, s[np.lexsort((s.imag, -s.real, np.abs(s)))], rtol=rtol)
    if "verdict" in exp:
        assert a.modes.verdict == exp["verdict"]


@pytest.mark.parametrize("path", CASE_FILES, ids=lambda p: p.stem)
def test_case_invariants(path):
    """Invariants on every case: Φ(q0) = 0, Φ_q N = 0, NᵀN = I, backward errors ≤ 1e-12,
    and the listed eigenvalues agree with the first-order state matrix (independent solver)."""
    a = analyze(path)
    model, eq, lin, md = a.model, a.eq, a.linear, a.modes
    if isinstance(model, mbseig.Model) and model.n_constraints:
        assert np.max(np.abs(model.phi(eq.q) / model.constraint_scales())) < 1e-12
        assert np.abs(model.phi_q(eq.q) @ lin.N).max() < 1e-12
    np.testing.assert_allclose(lin.N.T @ lin.N, np.eye(lin.dof), atol=1e-12)
    assert np.all(md.backward_error <= 1e-12)
    lam = np.linalg.eigvals(lin.state_matrix())
    for s in md.eigenvalues:
        # distance to the nearest state-matrix eigenvalue, relative to the spectrum's scale
        assert np.min(np.abs(lam - s)) <= 1e-7 * max(1.0, np.abs(lam).max())
