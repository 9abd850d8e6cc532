"""Smoke test of ``mbseig bench --quick`` on its fastest sections (no timing is asserted; the
benchmark itself is never part of the test suite)."""

import json

import pytest

from mbseig.cli import main


def test_bench_quick_writes_report(tmp_path, capsys):
    assert main(["bench", "--quick", "--out", str(tmp_path), "--sections", "dense", "constraint",
                 "jacobians", "failures"]) == 0
    md = (tmp_path / "benchmarks.md").read_text()
    for heading in ("## Targets", "## Dense eigensolvers", "## Jacobians",
                    "## Stability where methods fail"):
        assert heading in md
    assert (tmp_path / "speed_accuracy.png").stat().st_size > 1000
    res = json.loads((tmp_path / "benchmarks.json").read_text())
    methods = {r["method"] for r in res["rows"] if r["section"] == "dense"}
    assert {"naive companion", "QZ unscaled", "QZ scaled", "mbseig companion", "mbseig default",
            "LAPACK geev (floor)"} <= methods
    # every mbseig dense path meets its backward-error target on the chain family
    assert all(r["eta"] <= 1e-12 for r in res["rows"] if r["method"].startswith("mbseig"))
    assert all(f["naive_wrong"] and f["mbseig_right"] for f in res["failures"])
    # the machine's load is stated, as recorded at the start and at the end of the run
    for k in ("start", "end"):
        assert len(res["load"][k]) == 3 and all(x >= 0 for x in res["load"][k])
    said = ", ".join(f"{x:.2f}" for x in res["load"]["start"])
    assert f"Load average (1, 5, 15 min): {said} at the start and " in md


def test_bench_quick_large_section(tmp_path, capsys):
    """The large constrained model (general damping against the eigsh floor, each in a fresh
    process): present, verified (η, coverage), ratios formed."""
    assert main(["bench", "--quick", "--out", str(tmp_path), "--sections", "large"]) == 0
    res = json.loads((tmp_path / "benchmarks.json").read_text())
    large = {r["method"]: r for r in res["rows"] if r["section"] == "large"}
    assert {"floor", "partial-companion"} <= set(large)
    general = large["partial-companion"]
    assert general["m"] == 199 and general["eta"] <= 1e-12 and general["verified"]
    assert general["ratio"] > 0 and large["floor"]["ratio"] == 1.0
    # the general path's lowest |s| and the undamped floor's ω₁ agree to the damping's effect
    # (ζ below 1e-2 on this model: |s₁| = ω₁ to within 1e-3 relative)
    assert abs(general["omega_1"] - large["floor"]["omega_1"]) <= 1e-3 * large["floor"]["omega_1"]
    md = (tmp_path / "benchmarks.md").read_text()
    assert "## Large constrained model" in md


def test_bench_startup_rows_follow_the_method(tmp_path, capsys, monkeypatch):
    """The start-up rows' method (mbseig.bench.startup_rows.bench_startup), not a time: the
    process timer is replaced by one that records each call and returns set times, so that
    what is checked is which commands run, in which order, under which environment, and how
    the ratios are formed (median over repeats of the pair ratio, its spread, cpu apart)."""
    from mbseig.bench import startup_rows as su

    monkeypatch.setenv("OPENBLAS_CORETYPE", "Haswell")
    monkeypatch.setenv("OPENBLAS_L2_SIZE", "1048576")
    monkeypatch.setenv("PYTHONDONTWRITEBYTECODE", "1")
    calls = []
    # floor 1.0 s, 1.1, 0.9 by repeat (after the warm-up round); the command 1.2× its floor in
    # the first timed repeat, 1.1× in the second and 1.3× in the third: pair median 1.2×
    floor_t = iter([0.5, 1.0, 1.1, 0.9])
    modes_t = iter([0.5, 1.2, 1.21, 1.17])

    def fake(cmd, env):
        calls.append((tuple(cmd), env))
        if cmd[-1] == "import numpy, scipy.linalg":
            return next(floor_t), 0.25
        if cmd[-2] == "modes":
            return next(modes_t), 0.30
        return 0.4, 0.2

    monkeypatch.setattr(su, "timed_process", fake)
    assert main(["bench", "--quick", "--out", str(tmp_path), "--sections", "startup",
                 "--repeats", "3"]) == 0
    res = json.loads((tmp_path / "benchmarks.json").read_text())
    rows = {r["method"]: r for r in res["rows"] if r["section"] == "startup"}
    floor, modes = rows[su.STARTUP_FLOOR], rows["mbseig modes hand_device"]
    assert set(rows) == {su.STARTUP_FLOOR, "import numpy, scipy.linalg, prompt exit",
                         "import mbseig", "mbseig modes hand_device",
                         "mbseig modes hand_device, normal exit"}
    assert floor["ratio"] == floor["ratio_min"] == floor["ratio_max"] == 1.0
    assert modes["ratio"] == pytest.approx(1.2, rel=1e-12)  # median of 1.2, 1.1, 1.3
    assert (modes["ratio_min"], modes["ratio_max"]) == pytest.approx((1.1, 1.3), rel=1e-12)
    assert modes["cpu_ratio"] == pytest.approx(1.2, rel=1e-12) and modes["repeats"] == 3
    assert modes["time"] == 1.2 and floor["time"] == 1.0  # medians of the timed runs only
    # every command under one environment, with the three variables dropped
    assert all(not set(su.STARTUP_UNSET) & set(env) for _, env in calls)
    assert len({id(env) for _, env in calls}) == 1
    # one warm-up round, then the order alternates between repeats
    names = [c for c, _ in calls]
    assert len(names) == 5 * 4 and names[5:10] == names[:5] and names[10:15] == names[4::-1]
    md = (tmp_path / "benchmarks.md").read_text()
    assert "## Start-up" in md and "median of pairs" in md and "OPENBLAS_CORETYPE" in md
    assert "1.20 (1.20 s; pairs 1.10–1.30, cpu 1.20)" in md


def test_timed_process_measures_a_real_process():
    """timed_process: a child's wall and cpu seconds (both > 0; the cpu of a process that
    sleeps is far below its wall), and a failing command raises."""
    import subprocess
    import sys

    from mbseig.bench.startup_rows import startup_env, timed_process

    wall, cpu = timed_process([sys.executable, "-c", "import time; time.sleep(0.3)"], startup_env())
    assert wall >= 0.3 and 0 < cpu < wall
    with pytest.raises(subprocess.CalledProcessError):
        timed_process([sys.executable, "-c", "raise SystemExit(3)"], startup_env())


def test_bench_beams_rows_against_the_closed_forms(tmp_path):
    """The beams section on a small comb (2 oblique cantilevers of 1 and 1.1 m, 16 elements
    each): its lowest 4 frequencies (the first bending mode of each bar in both planes) match
    the cantilever's closed form (Blevins table 8-1, βL = 1.8751) to the mesh error of cubic
    Hermite elements at 16 elements, (βh)⁴-order: measured 1.3e-7, bound 1e-5; the report
    renders the row."""
    from mbseig.bench.beam_rows import bench_beams
    from mbseig.bench.report import write_report

    rows = bench_beams(lambda s: None, beams=2, elements=16, repeats=1, n_modes=4)
    (row,) = rows
    assert row["n"] == 6 * 2 * 16 and row["solver"].startswith("partial")
    assert 0 < row["error"] <= 1e-5
    assert set(row["stages"]) == {"load", "equilibrium", "linearize", "modes"}
    write_report({"config": {"quick": True, "repeats": 1, "threads": 1}, "rows": rows,
                  "machine": {"python": "3", "numpy": "2", "scipy": "1", "cpus": 2,
                              "platform": "x"}, "elapsed": 1.0}, tmp_path)
    md = (tmp_path / "benchmarks.md").read_text()
    assert "## 3-D beams" in md and "| 2 × 16 elements | 192 | partial" in md


def test_bench_spatial_chain_reads_its_bodies(tmp_path):
    """The spatial section's model: 12 natural coordinates and 6 rigid-body conditions per body
    (DESIGN §2), N + 1 bushings; its first evaluation at the initial configuration satisfies
    Φ = 0 (the bodies are placed exactly: tolerance 1e-12 on unit-vector conditions)."""
    import numpy as np

    from mbseig.bench.spatial_rows import build_chain

    model, times = build_chain(20, tmp_path)
    assert model.n == 12 * 20 and model.n_constraints == 6 * 20 and len(model.forces) == 21
    assert np.max(np.abs(model.phi(model.q_init))) <= 1e-12
    assert set(times) == {"read + assemble", "first Φ, Φ_q, g, K, C", "floor"}


def test_bench_batch_rows_state_goal_and_floor(tmp_path):
    """The batch section's rows (issue 42's goals) say whether each goal is met from the rate
    or from the ratio to the EXUDYN floor, and the report prints both (no timing asserted: the
    rows are built from given times)."""
    from mbseig.bench.batch_rows import _row
    from mbseig.bench.report import write_report

    fast = _row("device C4 over f", 2000, [0.5, 0.6, 0.55], 1, 3000.0, statics=["batch"])
    slow = _row("spatial double pendulum over m1 × l1", 100, [1.0], 0, floor=2e-4)
    assert fast["met"] and fast["rate"] == 2000 / 0.55 and fast["spread"] == (0.5 / 0.55,
                                                                              0.6 / 0.55)
    assert not slow["met"] and slow["ratio"] == (1.0 / 100) / 2e-4
    write_report({"config": {"quick": True, "repeats": 1, "threads": 1}, "rows": [fast, slow],
                  "machine": {"python": "3", "numpy": "2", "scipy": "1", "cpus": 2,
                              "platform": "x"}, "elapsed": 1.0}, tmp_path)
    md = (tmp_path / "benchmarks.md").read_text()
    assert "## Many points at once" in md
    assert "| device C4 over f |" in md and "| yes |" in md
    assert "(floor 0.200 ms: 50.0×) | **no** |" in md
