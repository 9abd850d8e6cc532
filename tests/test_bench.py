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
