"""Huge, tiny and non-finite numbers in the bundled cases end in an answer or in one line.

Each bundled case with each numeric value in turn set to 1e308, -1e308, 1e-308, inf, -inf and
nan, run through ``mbseig modes CASE --json`` with warnings as errors, must exit 0 with strict
JSON and nothing on stderr, or exit 2 with exactly one line ``mbseig: ...``.  The whole sweep
(every value of every case) is run by hand before a release; this test runs a fast,
representative part of it: the variants that once leaked a numpy warning before their refusal
(a periodic case whose period is 2π/w with w = 1e308: the trigonometric interpolant's
frequencies 2πk/T overflowed), the same with w large but finite (the motion's acceleration),
and a derandomized sample of the other values of a few quick cases."""

from __future__ import annotations

import json
import math
import tomllib

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from conftest import CASES
from mbseig.cli import main

pytestmark = pytest.mark.filterwarnings("error")

VALUES = [1e308, -1e308, 1e-308, math.inf, -math.inf, math.nan]
QUICK = ["pendulum.toml", "four_bar.toml", "rigid_rotor.toml", "spherical_pendulum.toml",
         "chain_damped.toml", "inverted_pendulum_shaken_pivot.toml"]


def _toml(v):
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, float):
        return {"nan": "nan", "inf": "inf", "-inf": "-inf"}.get(repr(v), repr(v))
    if isinstance(v, (int, str)):
        return json.dumps(v)
    if isinstance(v, list):
        return "[" + ", ".join(_toml(x) for x in v) + "]"
    return "{" + ", ".join(f"{json.dumps(k)} = {_toml(x)}" for k, x in v.items()) + "}"


def _leaves(x, path=()):
    """Paths of the numbers of a case (not ``[expected]``, which no command reads as input)."""
    if isinstance(x, bool):
        return []
    if isinstance(x, (int, float)):
        return [path]
    items = x.items() if isinstance(x, dict) else enumerate(x) if isinstance(x, list) else ()
    return [p for k, v in items if not (path == () and k == "expected")
            for p in _leaves(v, path + (k,))]


def _variant(tmp_path, name, path, value):
    data = tomllib.loads((CASES / name).read_text())
    node = data
    for key in path[:-1]:
        node = node[key]
    node[path[-1]] = value
    out = tmp_path / name
    out.write_text("".join(f"{json.dumps(k)} = {_toml(v)}\n" for k, v in data.items()))
    return out


def _contract(capsys, path):
    code = main(["modes", str(path), "--json"])
    out, err = capsys.readouterr()
    if code == 0:
        json.loads(out, parse_constant=lambda c: pytest.fail(f"{c} in the JSON"))
        assert err == ""
    else:
        assert code == 2, err
        assert err.endswith("\n") and err.count("\n") == 1 and err.startswith("mbseig: "), err
    return code, err


@pytest.mark.parametrize("name, key, value, words", [
    ("inverted_pendulum_shaken_pivot.toml", "w", 1e308, ["motion.period", "shorter than"]),
    ("asymmetric_rotor_anisotropic_bearings.toml", "Omega", 1e308, ["motion.period"]),
    ("inverted_pendulum_shaken_pivot.toml", "w", 1e-200, ["motion.period", "longer than"]),
    ("inverted_pendulum_shaken_pivot.toml", "w", 1e100, ["'O'", "second time derivative"]),
    ("inverted_pendulum_shaken_pivot.toml", "w", 1e72, ["'O'", "second time derivative"]),
    ("pendulum_shaken_pivot.toml", "w", 1e150, ["second time derivative"]),
])
def test_periodic_overflow_is_one_line(tmp_path, capsys, name, key, value, words):
    """The variants that leaked a numpy warning and a traceback from the periodic model: the
    period 2π/w below the shortest the model holds (the interpolant's frequencies overflowed),
    above the longest (the squared step of its time differences overflowed: "invalid value"), or
    a pivot's acceleration A w² beyond 3e138 (DOP853's error norm of it overflowed, w = 1e72);
    now one line naming the file and the element."""
    code, err = _contract(capsys, _variant(tmp_path, name, ("parameters", key), value))
    assert code == 2 and str(tmp_path / name) in err and all(w in err for w in words), err


@settings(max_examples=12, derandomize=True, deadline=None, database=None,
          suppress_health_check=list(HealthCheck))
@given(data=st.data())
def test_hostile_numbers_of_quick_cases(tmp_path_factory, capsys, data):
    """A derandomized sample of (case, number, hostile value) over a few quick cases."""
    name = data.draw(st.sampled_from(QUICK), label="case")
    paths = _leaves(tomllib.loads((CASES / name).read_text()))
    path = data.draw(st.sampled_from(paths), label="number")
    value = data.draw(st.sampled_from(VALUES), label="value")
    _contract(capsys, _variant(tmp_path_factory.mktemp("v"), name, path, value))
