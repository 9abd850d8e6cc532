"""Every bundled case with a steady [motion] against the values its [expected] table states
(the source of each is named in the case file): the modes as ``mbseig modes --json`` lists them
(``steady_modes``, rigid-body zeros included), the verdict, the wheels' normal forces and spins,
and the boundaries of ``mbseig sweep`` over the stated range (``tol`` each).  Tolerances are the
case's ``rtol`` / ``atol``."""

import json

import numpy as np
import pytest
from conftest import CASES
from expected import _series

from mbseig.casefile import motion_kind, read_case
from mbseig.casefile.expr import evaluate
from mbseig.cli import main
from mbseig.studies.pipeline import as_spec
from mbseig.studies.steady_modes import analyze_steady

STEADY = sorted(p for p in CASES.glob("*.toml") if motion_kind(read_case(p).data) == "steady")


def test_bundled_steady_cases_exist():
    assert {p.stem for p in STEADY} >= {"rolling_disk", "rolling_disk_turn", "whipple_bicycle"}


@pytest.mark.parametrize("path", STEADY, ids=lambda p: p.stem)
def test_steady_case_expected_values(path, capsys):
    spec = as_spec(path)
    assert main(["modes", str(path), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    exp = spec.data["expected"]
    assert exp.get("source") and spec.data.get("source")
    params = out["parameters"]
    rtol, atol = exp.get("rtol", 1e-10), exp.get("atol", 0.0)
    got = np.array([complex(*m["eigenvalue"]) for m in out["modes"]])
    ref = np.array([complex(re, im)
                    for re, im in _series(exp["steady_modes"], params, ["re", "im"])])
    assert got.size == ref.size
    # each within the case's tolerance plus its own stated error bound τ (an eigenvalue whose
    # reference is 0 and which is not a declared direction is computed, not deflated: its
    # distance from 0 is rounding residue within τ)
    bound = rtol * np.abs(ref) + atol + np.array([m["tolerance"] for m in out["modes"]])
    assert np.all(np.abs(got - ref) <= bound), (got, ref, bound)
    assert out["verdict"] == exp["steady_verdict"]
    forces = {c["name"]: c["force"] for c in out["contacts"]}
    for name, formula in exp.get("contact_forces", {}).items():
        assert forces[name] == pytest.approx(evaluate(formula, params), rel=1e-12)
    assert all(c["active"] for c in out["contacts"])
    if "spins" in exp:
        np.testing.assert_allclose(out["spins"], [evaluate(x, params) for x in exp["spins"]],
                                   rtol=1e-12)


BOUNDARIES = [(p, k) for p in STEADY for k in range(len(read_case(p).data["expected"]
                                                         .get("boundaries", [])))]


@pytest.mark.parametrize("path,k", BOUNDARIES, ids=lambda x: getattr(x, "stem", str(x)))
def test_steady_case_boundaries(path, k, tmp_path, capsys):
    """``mbseig sweep CASE --param v=START:STOP:COUNT`` finds the stated boundary to its tol."""
    b = read_case(path).data["expected"]["boundaries"][k]
    lo, hi, n = b["range"]
    args = ["sweep", str(path), "--param", f"{b['parameter']}={lo}:{hi}:{n}", "--json",
            "--no-progress", "--out", str(tmp_path)]
    assert main(args) == 0
    out = json.loads(capsys.readouterr().out)
    params = analyze_steady(as_spec(path)).model.parameters
    value = evaluate(b["value"], params)
    found = [x for x in out["boundaries"] if x["kind"] == b["kind"]]
    assert len(found) == 1, out["boundaries"]
    assert found[0]["stability"] == b["stability"]
    assert abs(found[0]["value"] - value) <= b["tol"], (found[0]["value"], value)
