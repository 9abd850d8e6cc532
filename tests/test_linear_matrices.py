"""Linear cases' matrix files (issue 17, the .npz/.mtx loader; issue 13 item 3): every bad file is
one CaseError naming the case file, the element and the matrix file, never a traceback; a complex
matrix is refused the same way by both loaders, never cast; subnormal and huge entries reach the
eigensolver, which handles them (tests/test_eigen_trust.py).  References: the rotating mass's
closed form s = ±i|ω₀ − Ω|, ±i(ω₀ + Ω) (cases/rotating_mass.toml) for the files that load.
"""

import warnings

import numpy as np
import pytest
import scipy.io
import scipy.sparse as sp

import mbseig
from mbseig.cli import main
from mbseig.errors import CaseError

CASE = """
schema_version = 1
kind = "linear"
title = "rotating mass from files"
source = "closed form: s = +/- i |omega0 - Omega|, +/- i (omega0 + Omega) \
with omega0 = 2, Omega = 3"
[matrices]
M = {{ file = "{m}", key = "M" }}
P = {{ file = "{p}", key = "P" }}
Q = {{ file = "{q}", key = "Q" }}
"""

M0 = np.eye(2)
P0 = 6.0 * np.array([[0.0, -1.0], [1.0, 0.0]])
Q0 = -5.0 * np.eye(2)


def write(tmp_path, *, npz=None, mtx=None, key_q="Q", files=None):
    """A linear case whose M, P come from good.npz and Q from ``files`` (default good.npz)."""
    np.savez(tmp_path / "good.npz", M=M0, P=P0, Q=Q0)
    q = files or "good.npz"
    text = CASE.format(m="good.npz", p="good.npz", q=q).replace('key = "Q"', f'key = "{key_q}"')
    if q.endswith(".mtx"):
        text = text.replace(f'{{ file = "{q}", key = "{key_q}" }}', f'{{ file = "{q}" }}')
    path = tmp_path / "case.toml"
    path.write_text(text)
    return path


def refused(path, capsys, *needles):
    """Exit 2 with one line naming the case file, the element and each needle; no warning."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert main(["modes", str(path)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1, err
    assert str(path) in err[0] and "matrices.Q" in err[0]
    for n in needles:
        assert n in err[0], err[0]
    return err[0]


def test_good_files_load(tmp_path):
    """.npz and .mtx give the closed-form eigenvalues (rtol 1e-12)."""
    for q in ("good.npz", "q.mtx"):
        scipy.io.mmwrite(str(tmp_path / "q.mtx"), Q0)
        md = mbseig.modes(mbseig.load_case(write(tmp_path, files=q)).M, P0,
                          mbseig.load_case(write(tmp_path, files=q)).Q)
        np.testing.assert_allclose(md.omega_n, [1.0, 5.0], rtol=1e-12)


@pytest.mark.parametrize("fmt", ["npz", "mtx"])
def test_complex_matrix_refused_on_both_loaders(tmp_path, capsys, fmt):
    """NLEVP power_plant style (1 + 0.2i)K: refused with the same rule by both loaders,
    naming the entry; exact-zero imaginary parts are real and load."""
    Qc = (1 + 0.2j) * Q0
    if fmt == "npz":
        np.savez(tmp_path / "c.npz", Q=Qc)
        path = write(tmp_path, files="c.npz")
    else:
        scipy.io.mmwrite(str(tmp_path / "c.mtx"), Qc)
        path = write(tmp_path, files="c.mtx")
    line = refused(path, capsys, f"c.{fmt}", "complex entry (0, 0)", "real M, P, Q")
    assert "ComplexWarning" not in line
    np.savez(tmp_path / "r.npz", Q=Q0.astype(complex))
    case = mbseig.load_case(write(tmp_path, files="r.npz"))
    assert case.Q.dtype == float and np.array_equal(case.Q, Q0)


@pytest.mark.parametrize("kind, needle", [
    ("truncated", "cannot be read as a npz matrix file"),
    ("empty", "the file is empty"),
    ("nonsquare", "square and non-empty, got shape 2×3"),
    ("zero", "square and non-empty, got shape 0×0"),
    ("object", "cannot be read as a npz matrix file"),
    ("bigint", "is not exactly a double"),
    ("missing", "no array 'Q' (it has K)"),
    ("nan", "entry (1, 1) = nan is not finite"),
    ("strings", "are not numbers"),
])
def test_bad_npz_files(tmp_path, capsys, kind, needle):
    f = tmp_path / "bad.npz"
    if kind == "truncated":
        np.savez(f, Q=Q0)
        f.write_bytes(f.read_bytes()[:60])
    elif kind == "empty":
        f.write_bytes(b"")
    elif kind == "nonsquare":
        np.savez(f, Q=np.ones((2, 3)))
    elif kind == "zero":
        np.savez(f, Q=np.zeros((0, 0)))
    elif kind == "object":
        np.savez(f, Q=np.array([[1, None], [None, 1]], dtype=object))
    elif kind == "bigint":
        np.savez(f, Q=np.array([[2**62, 0], [0, 1]], dtype=np.int64))
    elif kind == "missing":
        np.savez(f, K=Q0)
    elif kind == "nan":
        np.savez(f, Q=np.array([[1.0, 0.0], [0.0, np.nan]]))
    elif kind == "strings":
        np.savez(f, Q=np.array([["a", "b"], ["c", "d"]]))
    refused(write(tmp_path, files="bad.npz"), capsys, "bad.npz", needle)


@pytest.mark.parametrize("kind, needle", [
    ("truncated", "cannot be read as a mtx matrix file"),
    ("empty", "the file is empty"),
    ("nonsquare", "the header says 2×3"),
    ("huge", "beyond the 5000 of a linear case"),
])
def test_bad_mtx_files(tmp_path, capsys, kind, needle):
    f = tmp_path / "bad.mtx"
    if kind == "truncated":
        scipy.io.mmwrite(str(f), Q0)
        f.write_text(f.read_text()[:-12])
    elif kind == "empty":
        f.write_text("")
    elif kind == "nonsquare":
        scipy.io.mmwrite(str(f), np.ones((2, 3)))
    elif kind == "huge":  # a header claiming 1e9 rows: refused before any allocation
        f.write_text("%%MatrixMarket matrix coordinate real general\n"
                     "1000000000 1000000000 1\n1 1 1.0\n")
    refused(write(tmp_path, files="bad.mtx"), capsys, "bad.mtx", needle)


def test_subnormal_and_huge_entries_reach_the_solver(tmp_path):
    """A mass entry 5e-324 and a stiffness sum overflowing: the first is solved (no LAPACK
    'illegal value'; 2 infinite eigenvalues dropped and counted), the second refused as a
    matrix rule ("the sum of terms overflows")."""
    np.savez(tmp_path / "sub.npz", M=np.diag([5e-324, 1.0]), P=P0, Q=Q0)
    text = CASE.format(m="sub.npz", p="sub.npz", q="sub.npz")
    (tmp_path / "s.toml").write_text(text)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        a = mbseig.analyze(tmp_path / "s.toml")
    assert a.modes.n_infinite == 2 and a.modes.accounting["finite"] == 2
    big = text.replace('Q = { file = "sub.npz", key = "Q" }',
                       'Q = [{ factor = 1e308, matrix = { file = "sub.npz", key = "Q" } },'
                       ' { factor = 1e308, matrix = { file = "sub.npz", key = "Q" } }]')
    (tmp_path / "b.toml").write_text(big)
    with pytest.raises(CaseError, match="the sum of terms overflows"):
        mbseig.load_case(tmp_path / "b.toml")


def test_sparse_mtx_loads_dense(tmp_path):
    """A coordinate .mtx (sparse) loads as the same dense matrix (exactly)."""
    scipy.io.mmwrite(str(tmp_path / "q.mtx"), sp.csr_matrix(Q0))
    case = mbseig.load_case(write(tmp_path, files="q.mtx"))
    assert np.array_equal(case.Q, Q0)
