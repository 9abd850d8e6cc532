"""The package's shape (issue: one pipeline, one direction): the layers contract, no import
cycles, a case parsed once per study, and loading that solves nothing.

References: the contracts in pyproject.toml ([tool.importlinter]); the import graph that
import-linter builds (grimp); call counts, which are exact.
"""

from pathlib import Path

import numpy as np
import pytest

import mbseig
from mbseig.casefile import read_case
from mbseig.studies.sweep import run_sweep

ROOT = Path(__file__).resolve().parent.parent
CASES = ROOT / "cases"


def test_import_linter_contracts_kept():
    """`lint-imports` on pyproject.toml: the pipeline layers and 'stages never import the
    reader' hold (exit code 0; a backward import or a cycle between layers gives 1)."""
    from importlinter.cli import lint_imports

    assert lint_imports(config_filename=str(ROOT / "pyproject.toml"), no_cache=True,
                        no_logo=True) == 0


def test_contracts_hold_without_indirect_imports():
    """Every contract is checked on the whole import graph: none allows indirect imports (the
    report imports no computing stage even through another package)."""
    import tomllib

    contracts = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["importlinter"][
        "contracts"]
    names = {c["name"] for c in contracts}
    assert {"pipeline layers", "the report computes nothing"} <= names
    assert [c["name"] for c in contracts if c.get("allow_indirect_imports")] == []


def test_no_import_cycles():
    """No module of mbseig imports, directly or through others, a module that imports it."""
    grimp = pytest.importorskip("grimp")  # installed with import-linter
    graph = grimp.build_graph("mbseig")
    cycles = []
    for m in sorted(graph.modules):
        for imported in graph.find_modules_directly_imported_by(m):
            if graph.chain_exists(importer=imported, imported=m):
                cycles.append((m, imported))
    assert cycles == []


def test_sweep_of_100_points_parses_the_case_once(monkeypatch):
    """A 100-point sweep reads and parses its case file once (count of TOML parses: exactly 1);
    every point is rebuilt from the parsed content."""
    import mbseig.casefile as cf

    calls = []
    real = cf.tomllib.loads
    monkeypatch.setattr(cf.tomllib, "loads", lambda text: calls.append(1) or real(text))
    res = run_sweep(CASES / "pendulum.toml", [("g", np.linspace(1.0, 20.0, 100))], jobs=1)
    assert len(calls) == 1
    assert sum(len(line) for line in res.points) == 100
    assert not any(pt.get("error") for line in res.points for pt in line)


def test_loading_the_device_solves_nothing(monkeypatch):
    """Loading hand_device builds the model without evaluating a force or a constraint (no
    Newton solve); the inverse statics that sets the actuator runs in mbseig.equilibrium."""
    from mbseig.model.system import Model

    def forbidden(*args, **kwargs):
        raise AssertionError("the reader evaluated the model")

    with monkeypatch.context() as m:
        for name in ("generalized_force", "force_jacobians", "phi", "phi_q"):
            m.setattr(Model, name, forbidden)
        model = read_case(CASES / "hand_device.toml").build("C1")
    assert model.commands and not model.drivers  # the command is pending
    eq = mbseig.equilibrium(model)
    assert len(eq.model.drivers) == 1 and not eq.model.commands


def test_modes_accepts_a_linear_model():
    """mbseig.modes(lin) equals mbseig.modes(lin.M, lin.P, lin.Q, N=lin.N, ...) with the linear
    model's rigid-body directions and displayed coordinates (same path, same numbers: identical
    arrays)."""
    model = mbseig.load_case(CASES / "four_bar.toml")
    lin = mbseig.linearize(model, mbseig.equilibrium(model))
    a = mbseig.modes(lin)
    b = mbseig.modes(lin.M, lin.P, lin.Q, N=lin.N, coordinate_names=lin.coordinate_names,
                     rigid=lin.rigid, display=lin.display)
    assert a.solver == b.solver
    np.testing.assert_array_equal(a.eigenvalues, b.eigenvalues)
    np.testing.assert_array_equal(a.shapes, b.shapes)
    assert [d for d in a.dominant] == [d for d in b.dominant]


def test_plots_leave_the_backend_alone(tmp_path):
    """Drawing a pole map does not switch matplotlib's backend and registers no pyplot figure."""
    import matplotlib

    from mbseig import plots

    before = matplotlib.get_backend()
    fig = plots.pole_map(np.array([-1 + 2j, -0.5 + 0j]), stability=["stable", "stable"])
    path = plots.save(fig, tmp_path / "p.png")
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert matplotlib.get_backend() == before
    import matplotlib.pyplot as plt

    assert plt.get_fignums() == []


def test_two_configuration_report_parses_the_case_once(monkeypatch, tmp_path):
    """A report of two configurations of the finger device reads and parses the case file once
    (exact count: 1; it used to be parsed five times)."""
    import mbseig.casefile as cf
    from mbseig.studies.report_data import write_report

    calls = []
    real = cf.tomllib.loads
    monkeypatch.setattr(cf.tomllib, "loads", lambda text: calls.append(1) or real(text))
    md, page = write_report(CASES / "hand_device.toml", out_dir=tmp_path, configs=["C1", "C2"],
                            run_check=False, studies=False)
    assert len(calls) == 1 and md.exists() and page.exists()
