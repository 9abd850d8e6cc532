"""Smoke test of ``mbseig bench --quick`` on its fastest sections (no timing is asserted; the
benchmark itself is never part of the test suite)."""

import json

from mbseig.cli import main


def test_bench_quick_writes_report(tmp_path, capsys):
    assert main(["bench", "--quick", "--out", str(tmp_path), "--sections", "dense", "constraint",
                 "jacobians", "failures"]) == 0
    md = (tmp_path / "benchmarks.md").read_text()
    for heading in ("## Targets", "## Dense eigensolvers", "## Jacobians", "## Stability where methods fail"):
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


def test_bench_quick_large_and_startup_sections(tmp_path, capsys):
    """The large constrained model (general damping against the eigsh floor, each in a fresh
    process) and the start-up rows: present, verified (η, coverage), ratios formed."""
    assert main(["bench", "--quick", "--out", str(tmp_path), "--sections", "large", "startup"]) == 0
    res = json.loads((tmp_path / "benchmarks.json").read_text())
    large = {r["method"]: r for r in res["rows"] if r["section"] == "large"}
    assert {"floor", "partial-companion"} <= set(large)
    general = large["partial-companion"]
    assert general["m"] == 199 and general["eta"] <= 1e-12 and general["verified"]
    assert general["ratio"] > 0 and large["floor"]["ratio"] == 1.0
    # the general path's lowest |s| and the undamped floor's ω₁ agree to the damping's effect
    # (ζ below 1e-2 on this model: |s₁| = ω₁ to within 1e-3 relative)
    assert abs(general["omega_1"] - large["floor"]["omega_1"]) <= 1e-3 * large["floor"]["omega_1"]
    startup = [r for r in res["rows"] if r["section"] == "startup"]
    assert len(startup) == 4 and all(r["time"] > 0 for r in startup)
    md = (tmp_path / "benchmarks.md").read_text()
    assert "## Large constrained model" in md and "## Start-up" in md


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
