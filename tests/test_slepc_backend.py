"""The optional SLEPc backend of the partial path (``solver="partial-slepc"``) against the scipy
path on the same bordered model.

Model: a 1-D chain of 400 masses m_i = 1 + 0.5 sin i, springs k = 1000 to walls at both ends,
every 10th spring replaced by a rigid link (39 constraint rows x_{i+1} − x_i = 0), grounded
dashpots on every 7th mass plus stiffness-proportional damping: non-proportional, so the general
path runs.  Reference: ``partial-companion`` (ARPACK shift-invert Arnoldi, independent code and
factorization).  Tolerance 1e-9 relative on each eigenvalue: both paths verify η ≤ 1e-8 on the
bordered pencil; SLEPc's own stopping test is η ≤ 1e-14 (its norms), and κ of these modes is
below 1e3, so agreement to ~1e-10 is expected and 1e-9 leaves a margin without hiding a wrong
mode (the modes are separated by > 1e-2 relative).  Skipped where slepc4py cannot be imported
by any candidate Python (mbseig.eigen.slepc.slepc_python).
"""

import os
import shutil

import numpy as np
import pytest
import scipy.sparse as sp

from mbseig.eigen import solve_partial
from mbseig.eigen import slepc as slepc_mod
from mbseig.errors import SolverError


def _chain(n=400, every=10):
    i = np.arange(n)
    k = 1000.0
    K = sp.diags([2 * k * np.ones(n), -k * np.ones(n - 1), -k * np.ones(n - 1)], [0, 1, -1],
                 format="csr")
    cd = np.zeros(n)
    cd[::7] = 0.05
    C = (sp.diags(cd) + (0.002 / k) * K).tocsr()
    M = sp.diags(1 + 0.5 * np.sin(i), format="csr")
    a = np.arange(every - 1, n - 1, every)
    r = np.arange(a.size)
    G = sp.csr_matrix((np.r_[-np.ones(a.size), np.ones(a.size)], (np.r_[r, r], np.r_[a, a + 1])),
                      shape=(a.size, n))
    return M, C, K, G


needs_slepc = pytest.mark.skipif(not slepc_mod.slepc_available(), reason="slepc4py not importable")


@needs_slepc
def test_slepc_matches_scipy_partial_path():
    M, C, K, G = _chain()
    ref = solve_partial(M, C, K, G=G, n_modes=8, solver="partial-companion")
    got = solve_partial(M, C, K, G=G, n_modes=8, solver="partial-slepc")
    assert got.solver == "partial-slepc" and ref.solver == "partial-companion"
    assert got.details["slepc"]["nconv"] >= 17 and got.coverage["verified"]
    a, b = np.sort_complex(ref.eigenvalues), np.sort_complex(got.eigenvalues)
    assert a.size == b.size == 16  # 8 underdamped pairs
    np.testing.assert_allclose(b, a, rtol=1e-9)
    # SLEPc stops at its own η ≤ 1e-14 with its own matrix-norm estimates (not Frobenius):
    # measured here up to 5e-12 in mbseig's η; 1e-10 is still 100x below the path's verify_tol
    assert np.max(got.backward_error) <= 1e-10
    # mode shapes in full coordinates: the same up to a unit complex factor (MAC ≈ 1)
    ia, ib = np.argsort(ref.eigenvalues.imag), np.argsort(got.eigenvalues.imag)
    Xa, Xb = ref.vectors[:, ia], got.vectors[:, ib]
    mac = np.abs(np.sum(Xa.conj() * Xb, axis=0)) ** 2 / (np.sum(np.abs(Xa) ** 2, axis=0)
                                                          * np.sum(np.abs(Xb) ** 2, axis=0))
    assert np.all(mac > 1 - 1e-8)
    # the constraints hold on the returned modes: G x = 0 to rounding
    assert np.max(np.abs(G @ got.vectors)) <= 1e-10


@needs_slepc
def test_slepc_refuses_a_band():
    M, C, K, G = _chain(100)
    with pytest.raises(SolverError, match="lowest modes"):
        solve_partial(M, C, K, G=G, band=(1.0, 2.0), solver="partial-slepc")


def test_slepc_missing_is_one_clear_error(monkeypatch, tmp_path):
    """Without slepc4py the path is refused with the install hint, never a traceback: a named
    worker Python that does not exist, and one that exists but cannot import petsc4py (a
    script standing in for it that fails as such a Python fails)."""
    M, C, K, G = _chain(60)
    monkeypatch.setenv("MBSEIG_SLEPC_PYTHON", str(tmp_path / "no-such-python"))
    with pytest.raises(SolverError, match="python3-slepc4py.*no-such-python, which does not exist"):
        solve_partial(M, C, K, G=G, n_modes=3, solver="partial-slepc")
    fake = tmp_path / "python"
    fake.write_text("#!/bin/sh\necho \"ModuleNotFoundError: No module named 'petsc4py'\" >&2\n"
                    "exit 2\n")
    fake.chmod(0o755)
    monkeypatch.setenv("MBSEIG_SLEPC_PYTHON", str(fake))
    with pytest.raises(SolverError, match="python3-slepc4py.*No module named 'petsc4py'"):
        solve_partial(M, C, K, G=G, n_modes=3, solver="partial-slepc")


needs_mpi = pytest.mark.skipif(shutil.which("mpiexec") is None and shutil.which("mpirun") is None,
                               reason="no mpiexec")


@needs_slepc
@needs_mpi
def test_slepc_on_two_mpi_ranks_gives_the_one_rank_eigenvalues(monkeypatch):
    """``MBSEIG_SLEPC_RANKS=2``: the worker runs under mpiexec with rows split over two
    processes and MUMPS' parallel LU.  Reference: the same path on one rank (UMFPACK), an
    independent factorization of the same pencil; tolerance 1e-9 relative per eigenvalue, as
    above (both stop at SLEPc's η ≤ 1e-14, κ < 1e3).  Each rank's peak memory is reported."""
    M, C, K, G = _chain()
    one = solve_partial(M, C, K, G=G, n_modes=8, solver="partial-slepc")
    monkeypatch.setenv("MBSEIG_SLEPC_RANKS", "2")
    two = solve_partial(M, C, K, G=G, n_modes=8, solver="partial-slepc")
    info = two.details["slepc"]
    assert info["ranks"] == 2 and info["factor"] == "mumps" and len(info["peak_rss_mb"]) == 2
    assert one.details["slepc"]["ranks"] == 1
    np.testing.assert_allclose(np.sort_complex(two.eigenvalues), np.sort_complex(one.eigenvalues),
                               rtol=1e-9)
    assert two.coverage["verified"] and np.max(two.backward_error) <= 1e-10


@pytest.mark.parametrize("value", ["0", "two", "-1", "1.5"])
def test_slepc_ranks_must_be_a_positive_integer(monkeypatch, value):
    monkeypatch.setenv("MBSEIG_SLEPC_RANKS", value)
    with pytest.raises(SolverError, match="MBSEIG_SLEPC_RANKS must be a positive integer"):
        slepc_mod.slepc_ranks()


def test_a_killed_solve_leaves_no_scratch_behind(tmp_path):
    """A solve killed by SIGKILL cannot remove its scratch folder (in /dev/shm: memory); the next
    solve removes it.  Reference: the rule of ``reap_stale`` — a folder goes only when every
    process it names is gone; a live solve's folder, a folder without its list (being set up),
    another container's folder and other files stay."""
    import subprocess
    import sys

    gone = subprocess.Popen([sys.executable, "-c", "pass"])
    gone.wait()  # a PID that has just ended (not reused within this test)
    try:  # the owners file's first line: the PID namespace of the solve (Linux; "-" elsewhere)
        space = os.readlink("/proc/self/ns/pid").replace(" ", "")
    except OSError:
        space = "-"

    def folder(name, text):
        d = tmp_path / (slepc_mod.PREFIX + name)
        (d / "in").mkdir(parents=True)
        (d / "in" / "M_data.npy").write_bytes(b"x" * 1000)
        if text is not None:
            (d / "owners").write_text(text)
        return d

    dead = folder("dead", f"{space}\n{gone.pid}\n")
    live = folder("live", f"{space}\n{os.getpid()}\n{gone.pid}\n")
    unlisted = folder("setup", None)
    elsewhere = folder("other-ns", f"pid:[0]\n{gone.pid}\n")
    other = tmp_path / "unrelated"
    other.mkdir()
    (other / "owners").write_text(f"{space}\n{gone.pid}\n")
    removed = slepc_mod.reap_stale(str(tmp_path))
    assert removed == [str(dead)]
    assert not dead.exists()
    assert live.exists() and unlisted.exists() and elsewhere.exists() and other.exists()
    assert slepc_mod.reap_stale(str(tmp_path / "missing")) == []
