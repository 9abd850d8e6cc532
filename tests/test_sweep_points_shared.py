"""Lines of one sweep that differ only in damping share their statics (issue "Fast at every
size": sweeps at 300 points a second).

Reference throughout: every line followed on its own (``sweep_line`` without a share token:
its own builds, command resolves, branch and equilibrium records) — the computation before the
lines shared anything.  At rest a damping value multiplies a zero rate, so the shared statics
are the same floating-point operations on the same numbers: the tolerance is zero (bitwise
equal eigenvalues, postures, verdicts and records).
"""

from __future__ import annotations

import uuid
import warnings

import numpy as np
import pytest

import mbseig.studies.continuation as cont
from mbseig.casefile import read_case
from mbseig.studies import run_sweep
from mbseig.studies.continuation import sweep_line

from conftest import CASES

DEVICE = CASES / "hand_device.toml"
KEYS = ("eigenvalues", "q", "tol", "shapes", "verdict", "static", "statics", "segment",
        "branch_kind", "corrector_iterations", "iterations", "out_of_range", "solver", "error")


@pytest.fixture(scope="module")
def device():
    return read_case(DEVICE)


@pytest.fixture
def follows(monkeypatch):
    """The number of branches followed (one per line that does not share); lines are followed
    point by point (the batched line, which shares nothing and needs no sharing, is compared
    with this path in tests/test_batch_modes.py)."""
    monkeypatch.setattr(cont, "BATCH_LINES", False)
    calls = []
    real = cont.follow

    def counted(*a, **k):
        calls.append(1)
        return real(*a, **k)

    monkeypatch.setattr(cont, "follow", counted)
    return calls


def _same_point(a, b):
    for key in KEYS:
        x, y = a.get(key), b.get(key)
        if isinstance(x, np.ndarray) or isinstance(y, np.ndarray):
            assert np.array_equal(x, y), key
        else:
            assert x == y, key


def _lines(spec, config, axis, values, lines, share):
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            return [sweep_line(spec, config, line, axis, values, share=share) for line in lines]
    finally:
        cont.release(share)


def _assert_equal_lines(shared, alone):
    for s, a in zip(shared, alone, strict=True):
        assert len(s["points"]) == len(a["points"])
        for p, r in zip(s["points"], a["points"], strict=True):
            _same_point(p, r)
        assert s["record"] == a["record"]
        assert [e["type"] for e in s["events"]] == [e["type"] for e in a["events"]]
        assert [(b["p"], b["static"], b["verdict"], b["q"]) for b in s["branch"]] == \
            [(b["p"], b["static"], b["verdict"], b["q"]) for b in a["branch"]]


@pytest.mark.parametrize("config, axis, values, lines", [
    (None, "k_a", np.linspace(800.0, 1200.0, 5), [{"c_a": 5.0}, {"c_a": 7.0}, {"c_a": 9.0}]),
    ("C4", "f", np.linspace(0.0, 1.5, 5), [{"c_a": 5.0}, {"c_a": 9.0}]),
    ("C4", "f", np.linspace(0.0, 2.0, 4), [{"damping_scale": 1.0}, {"damping_scale": 0.1}]),
])
def test_damping_lines_share_the_statics_bitwise(device, follows, config, axis, values, lines):
    """The second axis enters damping values only: one branch is followed for all lines, and
    every line equals the line followed alone, bit for bit."""
    shared = _lines(device, config, axis, values, lines, share=uuid.uuid4().hex)
    assert len(follows) == 1  # the later lines took the first line's statics
    del follows[:]
    alone = _lines(device, config, axis, values, lines, share=None)
    assert len(follows) == len(lines)
    _assert_equal_lines(shared, alone)
    # the damping does change the modes: the lines are not copies of each other
    assert not np.array_equal(shared[0]["points"][1]["eigenvalues"],
                              shared[-1]["points"][1]["eigenvalues"])


def test_a_stiffness_line_is_followed_again(device, follows):
    """A second axis that enters a stiffness (k_mcp, a joint spring) changes the statics: each
    line follows its own branch (and equals the line alone)."""
    values = np.linspace(800.0, 1200.0, 4)
    lines = [{"k_mcp": 0.04}, {"k_mcp": 0.06}]
    shared = _lines(device, None, "k_a", values, lines, share=uuid.uuid4().hex)
    assert len(follows) == 2
    alone = _lines(device, None, "k_a", values, lines, share=None)
    _assert_equal_lines(shared, alone)


def test_run_sweep_general_path_shares_nothing(device, follows):
    """lean=False builds and resolves every value: no line shares (three branches followed);
    the lean sweep of the same grid follows one and gives the same eigenvalues to the
    lean-path tolerance of tests/test_lean_sweep.py (1e-12 relative)."""
    axes = [("k_a", np.linspace(800.0, 1200.0, 4)), ("c_a", [5.0, 7.0, 9.0])]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        general = run_sweep(device, axes, jobs=1, progress=False, curves=False, lean=False)
        assert len(follows) == 3
        lean = run_sweep(device, axes, jobs=1, progress=False, curves=False)
    assert len(follows) == 4
    for lg, ll in zip(general.points, lean.points, strict=True):
        for a, b in zip(lg, ll, strict=True):
            assert a["verdict"] == b["verdict"]
            sa, sb = np.sort_complex(a["eigenvalues"]), np.sort_complex(b["eigenvalues"])
            assert np.max(np.abs(sa - sb) / np.abs(sb)) <= 1e-12
