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
