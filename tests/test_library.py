"""mbseig from Python: sweep results as DataFrames with short reprs, progress bars that work
with ``progress=True``, and a one-line error within seconds when a Dask scheduler is not there.

Reference values: closed-form eigenvalues of decoupled oscillators s² + c s + k = 0 (tolerance
1e-12 relative); mode numbers as ``mbseig modes`` sorts them (ω_n, then δ).
"""

import io
import math
import socket
import subprocess
import sys
import time

import numpy as np
import pytest

from mbseig.errors import MbseigError
from mbseig.studies.runners import Runner, progress_bar
from mbseig.studies.sweep import run_sweep

CROSSING = """
schema_version = 1
kind = "linear"
description = "two decoupled oscillators; the second one's stiffness p sweeps through the first's"
[parameters]
p = 1.0
c = 0.02
[matrices]
M = [[1.0, 0.0], [0.0, 1.0]]
P = [["c", 0.0], [0.0, "c"]]
Q = [[4.0, 0.0], [0.0, "p"]]
[expected]
source = "closed form"
"""


@pytest.fixture(scope="module")
def sweep(tmp_path_factory):
    path = tmp_path_factory.mktemp("lib") / "cross.toml"
    path.write_text(CROSSING)
    return run_sweep(path, [("p", np.linspace(1.0, 9.0, 5))], jobs=1), path


def test_to_dataframe(sweep):
    pd = pytest.importorskip("pandas")
    res, _ = sweep
    df = res.to_dataframe()
    assert isinstance(df, pd.DataFrame)
    assert len(df) == 5 * 2  # 5 points × 2 listed modes (one row per pair)
    c = 0.02
    # mode numbers as `mbseig modes` at p = 1: mode 1 is the √p oscillator (ω_n = 1 < 2)
    first = df[df["p"] == 1.0].set_index("mode")
    assert first.loc[1, "omega_n"] == pytest.approx(1.0, rel=1e-12)
    assert first.loc[2, "omega_n"] == pytest.approx(2.0, rel=1e-12)
    # mode 2 (the e1 oscillator, k = 4) keeps its number through the crossing at p = 4
    m2 = df[df["mode"] == 2]
    np.testing.assert_allclose(m2["omega_n"], 2.0, rtol=1e-12)
    np.testing.assert_allclose(m2["zeta"], c / (2 * 2.0), rtol=1e-10)  # ζ = c / (2 ω_n)
    np.testing.assert_allclose(m2["fd_hz"], math.sqrt(4 - c * c / 4) / (2 * math.pi), rtol=1e-12)
    assert set(df.columns) >= {"p", "mode", "re", "im", "delta", "omega_n", "omega_d", "fn_hz",
                               "fd_hz", "zeta", "stable", "verdict"}
    assert df["stable"].all()


def test_to_dataframe_without_pandas(sweep, monkeypatch):
    res, _ = sweep
    monkeypatch.setitem(sys.modules, "pandas", None)  # import pandas raises ImportError
    with pytest.raises(MbseigError, match="needs pandas"):
        res.to_dataframe()


def test_short_repr(sweep):
    res, _ = sweep
    text = repr(res)
    assert text.startswith("<SweepResult cross") and "\n" not in text and len(text) < 300
    assert "p 1…9 (5)" in text and "0 boundaries" in text


def test_progress_true_draws_bars(sweep):
    """progress=True used to raise (a bool called as a callback); now tqdm bars with rate and
    time left."""
    _, path = sweep
    res = run_sweep(path, [("p", np.linspace(1.0, 9.0, 3))], jobs=1, progress=True)
    assert res.boundaries == []
    buf = io.StringIO()
    show = progress_bar(buf)
    for k in range(4):
        show("lines", k, 3)
    text = buf.getvalue()
    assert "3/3" in text and ("task/s" in text or "s/task" in text)  # rate shown


def test_progress_rejects_non_callables():
    with pytest.raises(MbseigError, match="progress must be"):
        Runner(jobs=1, progress="yes")


def _closed_port():
    """A local port nothing listens on (bound, then closed)."""
    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
    s.close()
    return port


def test_unreachable_scheduler_one_line_exit_2(sweep):
    pytest.importorskip("distributed")
    _, path = sweep
    addr = f"tcp://127.0.0.1:{_closed_port()}"
    t0 = time.monotonic()
    out = subprocess.run([sys.executable, "-m", "mbseig", "sweep", str(path), "--param",
                          "p=1:9:3", "--scheduler", addr, "--no-progress", "--out",
                          str(path.parent / "o")], capture_output=True, text=True, timeout=60)
    elapsed = time.monotonic() - t0
    assert out.returncode == 2, out.stderr
    lines = out.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("mbseig: ") and "Dask scheduler" in lines[0]
    assert "Traceback" not in out.stderr
    # the connection timeout is 4 s (the message says so); the wall clock includes starting
    # Python, mbseig and dask in the subprocess (≈ 5 s idle), so it is bounded loosely: the
    # library's default timeout of 30 s would exceed 25 s on its own
    assert "within 4 s" in lines[0]
    assert elapsed < 25.0
