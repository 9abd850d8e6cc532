"""``mbseig sweep`` over two parameters of a periodic case writes the stability chart (PNG and
the JSON grid of verdicts and max|μ|): the Ince–Strutt chart of the pendulum on a shaken pivot.

Reference: the principal tongue of Mathieu's equation, b_1(q) < a < a_1(q) (scipy.special
mathieu_a / mathieu_b, DLMF 28.2), mapped to the pivot frequency with a = 4g/(l w²), q = 2A/l
(derivation in cases/pendulum_shaken_pivot.toml): unstable for 2√(g/(l a_1)) < w < 2√(g/(l b_1)).
The case is undamped, so every point outside a tongue is critical (|μ| = 1 within its bound).
"""

import json
import math

import numpy as np
from conftest import CASES
from scipy.special import mathieu_a, mathieu_b

from mbseig.cli import main

CASE = CASES / "pendulum_shaken_pivot.toml"
G, L = 9.81, 1.0  # the case's g and l


def tongue(A):
    q = 2 * A / L
    return 2 * math.sqrt(G / (L * mathieu_a(1, q))), 2 * math.sqrt(G / (L * mathieu_b(1, q)))


def test_chart_puts_the_first_tongue_where_mathieu_says(tmp_path, capsys):
    """A coarse 6 × 2 grid (w from 5 to 8, A = 0.05 and 0.15, every point at least 0.06 rad/s
    from a tongue edge): each verdict is unstable exactly inside the principal tongue and
    critical outside; inside, max|μ| > 1 beyond its bound; each grid bracket where the verdict
    changes along w holds the Mathieu edge, has the flip kind (μ = −1) and is located to the
    Mathieu edge within 1e-8 relative; chart.png is a PNG and chart.json the grid that the
    command printed."""
    out_dir = tmp_path / "chart"
    assert main(["sweep", str(CASE), "--param", "w=5:8:6", "--param", "A=0.05:0.15:2",
                 "--out", str(out_dir), "--json", "--no-progress"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["parameters"] == ["w", "A"]
    ws, As = np.array(out["w"]), np.array(out["A"])
    checked = 0
    for i, w in enumerate(ws):
        for j, A in enumerate(As):
            lo, hi = tongue(A)
            assert min(abs(w - lo), abs(w - hi)) > 0.06  # the grid keeps off the edges
            inside = lo < w < hi
            assert out["verdicts"][i][j] == ("unstable" if inside else "critical"), (w, A)
            rho, b = out["spectral_radius"][i][j], out["error_bounds"][i][j]
            assert (rho - b > 1) if inside else (abs(rho - 1) <= b)
            checked += 1
    assert checked == 12
    edges = out["boundaries"]
    assert len(edges) == 4
    for e in edges:
        lo, hi = tongue(e["at"]["A"])
        edge = lo if e["stability"] == "loss" else hi
        assert e["bracket"][0] < edge < e["bracket"][1] and e["kind"] == "flip"
        # located along w to 1e-8 relative (Brent on det(I + Φ)): scipy's Mathieu edge
        assert abs(e["value"] - edge) <= 1e-8 * edge and e["method"].startswith("Brent"), e
    assert out["tolerances"]["boundaries"] == "located along w to 1e-08 relative"
    assert (out_dir / "chart.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    saved = json.loads((out_dir / "chart.json").read_text())
    assert saved["verdicts"] == out["verdicts"]


def test_chart_bad_ranges_one_line(tmp_path, capsys):
    """Three ranges, or one parameter swept twice: one line naming the file and --param, exit 2."""
    for argv in (["--param", "w=5:8:2", "--param", "A=0.1:0.2:2", "--param", "l=1:2:2"],
                 ["--param", "w=5:8:2", "--param", "w=6:7:2"]):
        assert main(["sweep", str(CASE), *argv, "--out", str(tmp_path), "--no-progress"]) == 2
        err = capsys.readouterr().err.strip()
        assert len(err.splitlines()) == 1 and err.startswith(f"mbseig: {CASE}: --param: "), err
