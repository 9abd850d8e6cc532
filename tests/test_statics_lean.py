"""The statics' shortcuts give the numbers of the general computation (issue: sweep and statics
speed).

Each shortcut is compared with the computation it replaces, run on the same input:

- ``Memo.least_squares`` (one least-squares solve per q) against
  :func:`mbseig.statics.linalg.multipliers` called afresh: bitwise equal λ, rank and method;
- ``StepScales.of`` (made once per device) against ``StepScales(model)``: bitwise equal;
- the statics' Newton judged converged at its start on a dense LU (or on a right-hand side of
  exact zeros) against the same Newton on the SVD alone: the same q and λ bitwise (q is the
  start in both), the correction within the tolerance;
- ``Family.known`` (the corrector's g, Φ, Φ_q seeding the record's cache) against fresh
  evaluations of the model: bitwise equal;
- ``held_tension`` with its cache of the device's Φ_q against it without: the same record;
- the sweep records' mapping view against :class:`mbseig.records.Record`'s own;
- the static-stability verdict of a non-symmetric K_r with a zero eigenvalue within the
  tolerance (Ziegler's pendulum at p = 1e99): undetermined, as the closed form says (below).
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from conftest import CASES

from mbseig.casefile import read_case
from mbseig.records import Record
from mbseig.statics import equilibrium
from mbseig.statics import newton as newton_module
from mbseig.statics.cache import Memo
from mbseig.statics.continuation import Family
from mbseig.statics.inverse import held_tension
from mbseig.statics.linalg import StepScales, multipliers
from mbseig.statics.newton import newton, settings_for
from mbseig.statics.stiffness import static_stability
from mbseig.studies.continuation import family_maker
from mbseig.studies.records import SweepPoint

SMALL_CASES = ("pendulum", "spherical_pendulum", "spatial_double_pendulum", "four_bar",
               "hand_device")


def _model(name, **params):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        m = read_case(CASES / f"{name}.toml").build(**params)
        return equilibrium(m).model, m


@pytest.mark.parametrize("name", SMALL_CASES)
def test_least_squares_once_equals_multipliers(name):
    """Reference: multipliers() on the same Φ_q and g; bitwise equal, with and without check."""
    model, _ = _model(name)
    q = np.asarray(model.q_init, float) + 1e-3  # off the equilibrium: λ is a real solve
    memo = Memo(model)
    for check in (True, False, True):
        ref = multipliers(memo.phi_q(q), memo.generalized_force(q), 1e-10, check=check)
        got = memo.least_squares(q, 1e-10, check)
        assert np.array_equal(got[0], ref[0]) and got[1:] == ref[1:]
    lam = memo.least_squares(q, 1e-10, False)[0]
    lam[:] = np.nan  # a copy: the kept λ is not changed by its users
    assert np.all(np.isfinite(memo.least_squares(q, 1e-10, False)[0]))


@pytest.mark.parametrize("name", SMALL_CASES)
def test_step_scales_of_equals_fresh(name):
    """Reference: StepScales(model) made anew; the kept one has the same arrays (bitwise) and
    is shared by a model with the same elements."""
    model, built = _model(name)
    kept, fresh = StepScales.of(model), StepScales(model)
    assert np.array_equal(kept.ell, fresh.ell) and kept.length == fresh.length
    assert (kept.D is None) == (fresh.D is None)
    if fresh.D is not None:
        assert (kept.D != fresh.D).nnz == 0 and np.array_equal(kept.inv_len, fresh.inv_len)
    if built.constraints == model.constraints and all(
            a is b for a, b in zip(built.constraints, model.constraints, strict=True)):
        assert StepScales.of(built) is kept


@pytest.mark.parametrize("name", SMALL_CASES)
def test_newton_converged_start_equals_svd_newton(name, monkeypatch):
    """Reference: the same Newton with the start's LU test switched off (SVD only).  q and λ
    bitwise equal; the iteration count equal; both corrections within xtol."""
    model, _ = _model(name)
    q0 = np.asarray(model.q_init, float)

    def solve():
        memo = Memo(model)
        s = settings_for(memo, q0, tol=1e-12, xtol=None, floor_tol=1e-8, max_iter=50,
                         rank_tol=1e-10)
        return newton(memo, q0, s), s

    taken = []
    judge = newton_module._converged_by_lu
    monkeypatch.setattr(newton_module, "_converged_by_lu",
                        lambda *a: taken.append(judge(*a)) or taken[-1])
    fast, s = solve()
    monkeypatch.setattr(newton_module, "_converged_by_lu", lambda *a, **k: None)
    ref, _ = solve()
    assert np.array_equal(fast.q, ref.q) and np.array_equal(fast.lam, ref.lam)
    assert fast.iterations == ref.iterations
    assert fast.correction <= s.xtol and ref.correction <= s.xtol
    if name in ("hand_device", "spatial_double_pendulum"):  # (LU; a zero right-hand side)
        assert taken and taken[0] is not None


def test_newton_away_from_equilibrium_is_the_svd_newton(monkeypatch):
    """A start that has not converged: the Newton is the SVD's from its first step (bitwise
    equal q after the iteration; reference: the start's LU test switched off)."""
    model, _ = _model("four_bar")
    q0 = np.asarray(model.q_init, float) + 0.01

    def solve():
        memo = Memo(model)
        s = settings_for(memo, q0, tol=1e-12, xtol=None, floor_tol=1e-8, max_iter=50,
                         rank_tol=1e-10)
        return newton(memo, q0, s)

    fast = solve()
    monkeypatch.setattr(newton_module, "_converged_by_lu", lambda *a, **k: None)
    ref = solve()
    assert fast.iterations == ref.iterations > 0
    assert np.array_equal(fast.q, ref.q) and np.array_equal(fast.lam, ref.lam)


def test_family_known_equals_fresh_evaluations():
    """Reference: g, Φ and Φ_q evaluated afresh on the model at the same q (bitwise)."""
    spec = read_case(CASES / "hand_device.toml")
    make, _ = family_maker(spec, None, {}, "k_a")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        eq0 = equilibrium(make(800.0), offer_stable=False, self_stress="report")
    fam = Family(make, 400.0, eq0.model, eq0.q)
    y = fam.start(eq0.q, 800.0)
    y2 = y + 1e-6
    fam.R(y2, 900.0)
    fam.R(y2, 800.0)  # the model at another value: g its own, Φ and Φ_q shared
    known = fam.known(900.0, y2[:fam.n])
    assert set(known) == {"g", "phi", "phi_q"}
    model, q = fam.model(900.0), y2[:fam.n]
    assert np.array_equal(known["g"], model.generalized_force(q))
    assert np.array_equal(known["phi"], model.phi(q))
    assert np.array_equal(np.asarray(known["phi_q"]), np.asarray(model.phi_q(q, dense=True)))
    assert not np.array_equal(fam.known(800.0, q)["g"], known["g"])  # k_a enters g
    memo = Memo(model, q=q, known=known)
    assert memo.generalized_force(q) is known["g"]


def test_held_tension_cache_gives_the_same_record():
    """Reference: held_tension without its cache, at each value (the same model record)."""
    spec = read_case(CASES / "hand_device.toml")
    make, state = family_maker(spec, None, {}, "k_a")
    for v in (800.0, 900.0):
        make(v)
    assert state["checked"] and state["last"] is not None
    cache = {}
    for v in (950.0, 1000.0, 1100.0):
        built = state["lean"].make(v)  # the lean model (unchanged elements shared)
        a = held_tension(built, state["last"], cache=cache)
        b = held_tension(built, state["last"])
        assert a is not None and b is not None
        assert a.drivers == b.drivers
        assert [f.free_length for f in a.forces if hasattr(f, "free_length")] == \
            [f.free_length for f in b.forces if hasattr(f, "free_length")]
    assert "device_phi_q" in cache


def test_sweep_record_mapping_equals_record_mixin():
    """Reference: mbseig.records.Record's keys/get/[]/in on the same record."""
    pts = [SweepPoint(params={"p": 1.0}, error=None, eigenvalues=np.zeros(2), verdict="stable",
                      q=np.ones(3), iterations=2),
           SweepPoint.failed({"p": 2.0}, "failed: reason")]
    for pt in pts:
        assert pt.keys() == Record.keys(pt)
        for key in ("params", "error", "verdict", "static", "segment", "nonexistent", "q"):
            assert (key in pt) == Record.__contains__(pt, key)
            assert pt.get(key, "default") is Record.get(pt, key, "default")
            if Record.__contains__(pt, key):
                assert pt[key] is Record.__getitem__(pt, key)
            else:
                with pytest.raises(KeyError):
                    pt[key]


def test_ziegler_stiffness_at_huge_load_is_undetermined():
    """Ziegler's pendulum (cases/ziegler_pendulum.toml, m = l = k = 1) at p = 1e99.

    Closed form (the case's source): with absolute rod angles, K = [[2k − P l, P l − k],
    [−k, k]], det K = k² > 0 and trace K = 3k − P l < 0: two negative real eigenvalues, −P l
    and −k²/(P l) to first order, an even index, so statics proves no divergence (the modes
    decide).  In floating point P l ± k = P l: the small eigenvalue is rounding, within the
    stiffness tolerance of zero; the verdict must not count it (an odd index claimed a
    divergence "for any mass and damping").  At p = 1 (below flutter, K_r with a positive
    determinant and a positive trace 3 − p) the verdict stays as it was: stable."""
    for p, verdict in ((1e99, "undetermined"), (1.0, "stable")):
        model, _ = _model("ziegler_pendulum", p=p)
        q = np.asarray(model.q_init, float)
        lam = multipliers(model.phi_q(q, dense=True), model.generalized_force(q), 1e-10,
                          check=False)[0]
        st = static_stability(model, q, lam)
        assert st["verdict"] == verdict, (p, st)
        if p > 1e90:
            assert st["symmetric"] is False and st["zero"] >= 1 and st["index"] == 1


def test_report_says_why_statics_cannot_decide():
    """The report's statics paragraph gives the reason the verdict was left undetermined: at
    p = 1e99 (above) an eigenvalue within tolerance of zero, not the even count of negative
    eigenvalues that a non-symmetric stiffness with det K_r > 0 has."""
    import mbseig
    from mbseig.report.sections import statics_text

    text = statics_text(mbseig.equilibrium(mbseig.load_case(CASES / "ziegler_pendulum.toml",
                                                            p=1e99)))
    assert "within its tolerance of zero" in text and "even number" not in text
