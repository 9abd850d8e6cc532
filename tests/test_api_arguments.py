"""The public Python API checks its arguments (issue 38): one TypeError or ValueError naming the
function and the argument, what it expects and the value given, before any computation
(mbseig.arguments).  Table-driven: each row is one wrong argument of one function.

Reference: the rule of each argument as the function's docstring states it (a tolerance is a
positive number, ``axes`` a list of (name, values) pairs, ...).  Valid calls are exercised by
the rest of the suite (every case through load_case, equilibrium, linearize, modes, ...).
"""

import inspect
from pathlib import Path

import numpy as np
import pytest

import mbseig
from mbseig.arguments import RULES, ArgumentError
from mbseig.cli import main

ROOT = Path(__file__).resolve().parent.parent
PENDULUM = ROOT / "cases" / "pendulum.toml"


@pytest.fixture(scope="module")
def stages():
    """The pendulum through every stage: (model, eq, lin, modes)."""
    model = mbseig.load_case(PENDULUM)
    eq = mbseig.equilibrium(model)
    lin = mbseig.linearize(model, eq)
    return model, eq, lin, mbseig.modes(lin)


I2 = np.eye(2)

# (function, argument, call(stages) with that argument wrong, exception type)
ROWS = [
    ("read_case", "path", lambda s: mbseig.read_case(3), TypeError),
    ("read_case", "path", lambda s: mbseig.read_case(["a.toml"]), TypeError),
    ("load_case", "path", lambda s: mbseig.load_case(None), TypeError),
    ("load_case", "config", lambda s: mbseig.load_case(PENDULUM, config=3), TypeError),
    ("load_case", "params['m']", lambda s: mbseig.load_case(PENDULUM, m=[1.0]), TypeError),
    ("load_case", "params['m']", lambda s: mbseig.load_case(PENDULUM, m=float("nan")),
     ValueError),
    ("equilibrium", "model", lambda s: mbseig.equilibrium(str(PENDULUM)), TypeError),
    ("equilibrium", "tol", lambda s: mbseig.equilibrium(s[0], tol="1e-9"), TypeError),
    ("equilibrium", "tol", lambda s: mbseig.equilibrium(s[0], tol=-1.0), ValueError),
    ("equilibrium", "max_iter", lambda s: mbseig.equilibrium(s[0], max_iter=2.5), TypeError),
    ("equilibrium", "max_iter", lambda s: mbseig.equilibrium(s[0], max_iter=0), ValueError),
    ("equilibrium", "self_stress", lambda s: mbseig.equilibrium(s[0], self_stress="x"),
     ValueError),
    ("equilibrium", "continuation", lambda s: mbseig.equilibrium(s[0], continuation="no"),
     TypeError),
    ("equilibrium", "q_init", lambda s: mbseig.equilibrium(s[0], q_init=np.ones(9)), ValueError),
    ("linearize", "model", lambda s: mbseig.linearize("x", s[1]), TypeError),
    ("linearize", "eq", lambda s: mbseig.linearize(s[0], "eq"), TypeError),
    ("linearize", "rank_tol", lambda s: mbseig.linearize(s[0], s[1], rank_tol="a"), TypeError),
    ("linearize", "rank_tol", lambda s: mbseig.linearize(s[0], s[1], rank_tol=0.0), ValueError),
    ("modes", "M", lambda s: mbseig.modes("abc", I2, I2), TypeError),
    ("modes", "M", lambda s: mbseig.modes(np.ones((2, 3)), I2, I2), ValueError),
    ("modes", "P", lambda s: mbseig.modes(I2, np.eye(3), I2), ValueError),
    ("modes", "Q", lambda s: mbseig.modes(I2, I2, {"k": 1}), TypeError),
    ("modes", "solver", lambda s: mbseig.modes(I2, I2, I2, solver=3), TypeError),
    ("modes", "n_modes", lambda s: mbseig.modes(I2, I2, I2, n_modes="3"), TypeError),
    ("modes", "band", lambda s: mbseig.modes(I2, I2, I2, band=(5.0, 1.0)), ValueError),
    ("modes", "safety", lambda s: mbseig.modes(I2, I2, I2, safety=-1.0), ValueError),
    ("analyze", "case", lambda s: mbseig.analyze(), TypeError),
    ("analyze", "case", lambda s: mbseig.analyze(3), TypeError),
    ("analyze", "params", lambda s: mbseig.analyze(PENDULUM, params=[1]), TypeError),
    ("analyze", "model", lambda s: mbseig.analyze(model="pendulum"), TypeError),
    ("run_sweep", "axes", lambda s: mbseig.run_sweep(PENDULUM, {"m": np.linspace(1, 2, 3)}),
     TypeError),
    ("run_sweep", "axes", lambda s: mbseig.run_sweep(PENDULUM, [("m", 3.0)]), TypeError),
    ("run_sweep", "axes", lambda s: mbseig.run_sweep(PENDULUM, [("m", [1.0])]), ValueError),
    ("run_sweep", "axes", lambda s: mbseig.run_sweep(PENDULUM, [("m", [1.0, np.inf])]),
     ValueError),
    ("run_sweep", "jobs", lambda s: mbseig.run_sweep(PENDULUM, [("m", [1, 2])], jobs="2"),
     TypeError),
    ("run_sweep", "jobs", lambda s: mbseig.run_sweep(PENDULUM, [("m", [1, 2])], jobs=0),
     ValueError),
    ("run_sweep", "xtol_rel", lambda s: mbseig.run_sweep(PENDULUM, [("m", [1, 2])],
                                                         xtol_rel=-1e-10), ValueError),
    ("run_sweep", "progress", lambda s: mbseig.run_sweep(PENDULUM, [("m", [1, 2])],
                                                         progress="yes"), TypeError),
    ("check_modes", "model", lambda s: mbseig.check_modes("x", *s[1:]), TypeError),
    ("check_modes", "lin", lambda s: mbseig.check_modes(s[0], s[1], "lin", s[3]), TypeError),
    ("check_modes", "modes", lambda s: mbseig.check_modes(*s[:3], "md"), TypeError),
    ("check_modes", "indices", lambda s: mbseig.check_modes(*s, indices="1"), TypeError),
    ("check_modes", "indices", lambda s: mbseig.check_modes(*s, indices=[0]), ValueError),
    ("check_modes", "samples_per_period", lambda s: mbseig.check_modes(
        *s, samples_per_period=0), ValueError),
    ("check_modes", "method", lambda s: mbseig.check_modes(*s, method=None), TypeError),
    ("CaseBuilder", "dimension", lambda s: mbseig.CaseBuilder(dimension=True), TypeError),
    ("CaseBuilder", "dimension", lambda s: mbseig.CaseBuilder(dimension=4), ValueError),
    ("CaseBuilder", "title", lambda s: mbseig.CaseBuilder(dimension=2, title=5), TypeError),
]


@pytest.mark.parametrize("function,argument,call,kind", ROWS,
                         ids=[f"{f}-{a}-{i}" for i, (f, a, _, _) in enumerate(ROWS)])
def test_a_wrong_argument_is_named(stages, function, argument, call, kind):
    with pytest.raises(kind) as info:
        call(stages)
    assert isinstance(info.value, ArgumentError)  # raised by the check, not deep inside
    text = str(info.value)
    assert text.startswith(f"{function}: {argument} must be "), text
    assert " got " in text and "\n" not in text


def test_the_run_sweep_example_of_the_issue():
    """``run_sweep(spec, {"m1": values})`` failed with "unhashable type: 'slice'" deep in
    the sweep; now the message names axes, shows the form it takes and echoes the dict."""
    spec = mbseig.read_case(ROOT / "cases" / "hand_device.toml")
    with pytest.raises(TypeError, match=r"^run_sweep: axes must be a list of \(name, values\) "
                                        r"pairs, e\.g\. .*got \{'m1': array"):
        mbseig.run_sweep(spec, {"m1": np.linspace(0.0, 1.0, 3)})


def test_every_rule_names_an_argument_of_its_function():
    """The table cannot drift from the signatures: each checked name is a parameter."""
    from mbseig.casefile import load_case, read_case
    from mbseig.casefile.writer import CaseBuilder
    from mbseig.check import check_modes
    from mbseig.linear import linearize
    from mbseig.modal import modes
    from mbseig.statics import equilibrium
    from mbseig.studies import analyze, run_sweep

    functions = {"read_case": read_case, "load_case": load_case, "equilibrium": equilibrium,
                 "linearize": linearize, "modes": modes, "analyze": analyze,
                 "run_sweep": run_sweep, "check_modes": check_modes,
                 "CaseBuilder": CaseBuilder.__init__}
    assert set(RULES) == set(functions)
    for name, fn in functions.items():
        params = inspect.signature(fn).parameters
        missing = set(RULES[name]) - set(params)
        assert not missing, (name, missing)


def test_valid_calls_pass_the_check(stages):
    """The arguments the docstrings allow pass: numpy scalars for numbers, nested lists for
    matrices, a CaseSpec for a case, expressions for parameters."""
    spec = mbseig.read_case(PENDULUM)
    model = mbseig.load_case(PENDULUM, m="2*1.0", l=np.float64(1.0))
    eq = mbseig.equilibrium(model, tol=np.float64(1e-12), max_iter=np.int64(20),
                            q_init=list(model.q_init))
    md = mbseig.modes([[1.0, 0.0], [0.0, 2.0]], None, [[4.0, 0.0], [0.0, 9.0]],
                      n_modes=None, band=None)
    assert md.verdict == "critical" and eq.residual <= 1e-12
    res = mbseig.analyze(spec, params={"m": 1.5})
    assert res.modes.verdict == "critical"


def test_the_command_line_turns_an_argument_error_into_one_line(tmp_path, capsys):
    """A value the command line lets through to the API (here --jobs is checked by the parser
    itself) is one line and exit 2, never a traceback."""
    rc = main(["sweep", str(PENDULUM), "--param", "m=1:2:3", "--jobs", "0"])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and len(err) == 1 and "--jobs" in err[0] and "positive integer" in err[0]
