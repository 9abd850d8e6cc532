"""Steady motions analysed together (mbseig.studies.steady_batch) against the one-point path
(mbseig.studies.steady_modes.analyze_steady), and the steady sweep's root finder.

References:
- the wheels' batched kernels against each wheel's own methods (RollingWheel.velocity_jacobian,
  velocity_jacobian_q, gyroscopic, multiplier_stiffness): the same formulas in another order,
  products of a few O(1) numbers, so they agree to rounding; 1e-12 of the largest entry leaves
  three orders of margin over a dozen roundings of ε;
- the batch against analyze_steady on each point alone, an independent path (lstsq, scipy's
  null_space, the subset search of cyclic_directions, QZ): two computed eigenvalues of one exact
  eigenvalue lie within the sum of their stated bounds (each τ = 10 κ max(η, nε)|s| covers its
  own error), so matched eigenvalues must differ by at most τ₁ + τ₂, and the stabilities,
  verdicts and declared directions must be equal; normal forces are multipliers of one least-
  squares problem, solved backward-stably by both paths: they agree within c·κ(G)·ε of the
  largest (c = 100);
- boundaries of a sweep: each path returns a value within xtol + 4ε|x| of a sign change
  (brentq's guarantee, which _root keeps), so the two lie within twice that of each other;
- _root on functions with known roots (closed form): within xtol + rtol|x| of the root.
"""

from __future__ import annotations

import dataclasses
import warnings
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mbseig.casefile import read_case
from mbseig.casefile.element_readers import MotionUpdate
from mbseig.casefile.motion_readers import read_motion
from mbseig.model.rolling import wheels_of
from mbseig.model.stacked import ModelStack
from mbseig.studies import steady_sweep as sweep_module
from mbseig.studies.steady_batch import SteadyStack, _Wheel
from mbseig.studies.steady_modes import analyze_steady
from mbseig.studies.roots import RTOL
from mbseig.studies.roots import root_in_rounds as _root
from mbseig.studies.steady_sweep import steady_sweep

ROOT = Path(__file__).resolve().parents[1]
CASES = ROOT / "cases"
EXAMPLES = ROOT.parents[0] / "shared" / "examples"

# (case file, swept parameter, grid): the bundled steady motions; each grid crosses the case's
# boundaries (the bicycle's weave and capsize speeds, the disk's and the hoop's critical speeds)
LINES = [(CASES / "whipple_bicycle.toml", "v", np.linspace(0.5, 10.0, 40)),
         (CASES / "rolling_disk.toml", "v", np.linspace(0.2, 6.0, 30)),
         (CASES / "rolling_disk_turn.toml", "W", np.linspace(0.2, 0.8, 12)),
         (EXAMPLES / "rolling_hoop.toml", "v", np.linspace(0.2, 6.0, 30))]


def _spec(path):
    return read_case(path)


def test_wheel_kernels_equal_each_wheels_own_methods():
    rng = np.random.default_rng(7)
    for path in (CASES / "whipple_bicycle.toml", CASES / "rolling_disk.toml"):
        model = _spec(path).build(None)
        B = 5
        Q = model.q_init + 0.1 * rng.standard_normal((B, model.n))
        QD = rng.standard_normal((B, model.n))
        spin = rng.standard_normal(B)
        MU = rng.standard_normal((B, 2))
        for w in wheels_of(model):
            k = _Wheel(w)
            Z, ZD, QDw = k.frame(Q, QD)
            A, At = k.velocity(Z, ZD)
            g, dq, dqd, dO = k.gyroscopic(Z, QDw, spin)
            H = k.multiplier_stiffness(MU)
            for b in range(B):
                own = [w.velocity_jacobian(Q[b]), w.velocity_jacobian_q(Q[b], QD[b]),
                       *w.gyroscopic(Q[b], QD[b], spin[b]), w.multiplier_stiffness(MU[b])]
                got = [A[b], At[b], g[b], dq[b], dqd[b], dO[b], H[b]]
                for x, y in zip(got, own, strict=True):
                    scale = max(np.abs(y).max(), 1e-300)
                    assert np.abs(x - y).max() <= 1e-12 * scale


def test_stacked_wheel_rows_equal_the_models_own():
    """A wheel's holonomic rows are quadratic rows: the stack evaluates them by the quadratic
    kernel (not one model at a time) and gives the model's own Φ, Φ_q and H(λ)."""
    model = _spec(CASES / "whipple_bicycle.toml").build(None)
    stack = ModelStack([model])
    assert all(type(k).__name__ != "_Each" for *_, k in stack.constraints)
    rng = np.random.default_rng(3)
    Q = model.q_init + 0.05 * rng.standard_normal((4, model.n))
    L = rng.standard_normal((4, model.n_constraints))
    for b in range(4):
        for got, own in ((stack.phi(Q)[b], model.phi(Q[b])),
                         (stack.phi_q(Q)[b], np.asarray(model.phi_q(Q[b], dense=True))),
                         (stack.hessian(Q, L)[b],
                          np.asarray(model.constraint_hessian(Q[b], L[b], dense=True)))):
            assert np.abs(got - own).max() <= 1e-12 * max(np.abs(own).max(), 1.0)


def _matched(rows_a, rows_b):
    """Each non-declared row of a with the row of b of the nearest eigenvalue: (a, b)."""
    ra = [r for r in rows_a if not r.get("rigid_body")]
    rb = [r for r in rows_b if not r.get("rigid_body")]
    assert len(ra) == len(rb)
    for x in ra:
        s = complex(*x["eigenvalue"])
        yield x, min(rb, key=lambda y: abs(complex(*y["eigenvalue"]) - s))


@pytest.mark.parametrize("path,name,grid", LINES, ids=[p.stem for p, _, _ in LINES])
def test_batch_equals_the_one_point_path(path, name, grid):
    spec = _spec(path)
    model = spec.build(None, **{name: repr(float(grid[0]))})
    update = MotionUpdate(spec.data, None, {name: repr(float(grid[0]))}, name, model)
    assert update.reason is None
    stack = SteadyStack(model)
    assert stack.reason is None
    motions = [update.motion(repr(float(p))) for p in grid]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        got = stack.analyse(motions)
        ref = [analyze_steady(spec, params={name: repr(float(p))}) for p in grid]
    for p, r, a in zip(grid, got, ref, strict=True):
        assert not isinstance(r, str), f"{path.stem} at {name} = {p}: not covered ({r})"
        assert r.verdict == a.verdict
        assert r.n_rigid == len(a.cyclic.names)
        assert [x["rigid_body"] for x in r.modes if x["rigid_body"]] == \
            [x["rigid_body"] for x in a.modes if x["rigid_body"]]
        for x, y in _matched(r.modes, a.modes):
            d = abs(complex(*x["eigenvalue"]) - complex(*y["eigenvalue"]))
            assert d <= x["tolerance"] + y["tolerance"], (p, x["eigenvalue"], y["eigenvalue"])
            assert x["stability"] == y["stability"]
        # normal forces: one least-squares problem, backward-stable in both paths
        G = np.asarray(model.phi_q(a.state.q, dense=True))
        kappa = np.linalg.cond(G)
        forces = np.array([c["force"] for c in a.state.contacts])
        tol = 100 * kappa * np.finfo(float).eps * max(np.abs(forces).max(), 1.0)
        assert np.abs(np.array([c["force"] for c in r.contacts]) - forces).max() <= tol
        assert [c["active"] for c in r.contacts] == [c["active"] for c in a.state.contacts]


def test_points_the_batch_does_not_cover_take_the_one_point_path(monkeypatch):
    """A point the batch declines is analysed alone: the same record as the one-point task."""
    spec = _spec(CASES / "whipple_bicycle.toml")
    grid = [2.0, 4.0, 6.5]
    monkeypatch.setattr(SteadyStack, "analyse",
                        lambda self, motions, **kw: ["declined"] * len(motions))
    monkeypatch.setattr(sweep_module, "_LINES", {})
    line = sweep_module.SteadyLine(spec, None, {}, "v", grid[0])
    assert line.batch is None
    for p, got in zip(grid, line.points(grid), strict=True):
        own = sweep_module._steady_point(spec, None, {"v": repr(p)})
        assert got.verdict == own.verdict
        assert np.array_equal(got.eigenvalues, own.eigenvalues)


def test_a_mixed_batch_names_what_it_leaves():
    """Turning and straight motions in one batch: the turning ones are left, with the reason."""
    spec = _spec(CASES / "rolling_disk.toml")
    model = spec.build(None)
    m0 = read_motion(spec.data, dict(model.parameters))
    got = SteadyStack(model).analyse([m0, dataclasses.replace(m0, yaw_rate=0.1)])
    assert not isinstance(got[0], str)
    assert got[1] == "turning and straight points in one batch"


@pytest.mark.parametrize("path,name,grid", LINES, ids=[p.stem for p, _, _ in LINES])
def test_sweep_together_equals_point_by_point(path, name, grid, monkeypatch):
    spec = _spec(path)
    xtol = 1e-11
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        a = steady_sweep(spec, name, grid, jobs=1, progress=False, xtol=xtol)
        monkeypatch.setattr(sweep_module, "BATCH_STEADY", False)
        b = steady_sweep(spec, name, grid, jobs=1, progress=False, xtol=xtol)
    assert a.batch is None and b.batch == "switched off"
    assert [p["verdict"] for p in a.points] == [p["verdict"] for p in b.points]
    assert [(x["kind"], x["stability"]) for x in a.boundaries] == \
        [(x["kind"], x["stability"]) for x in b.boundaries]
    for x, y in zip(a.boundaries, b.boundaries, strict=True):
        assert abs(x["value"] - y["value"]) <= 2 * (xtol + RTOL * abs(y["value"]))


# ---- the root finder --------------------------------------------------------------------
def _evaluations(f):
    count = [0]

    def fun(ps):
        count[0] += len(ps)
        return [f(p) for p in ps]

    return fun, count


@pytest.mark.parametrize("many", [1, 8])
def test_root_of_a_smooth_function(many):
    root = 0.3
    f = lambda x: (x - root) * (1.0 + x * x)  # noqa: E731
    fun, _ = _evaluations(f)
    x = _root(fun, -1.0, 2.0, f(-1.0), f(2.0), 1e-12, many)
    assert abs(x - root) <= 1e-12 + RTOL * abs(x)


@pytest.mark.parametrize("many", [1, 8])
def test_root_of_a_jump_is_located_to_the_tolerance(many):
    """A sign change without a root (a jump): the bracket still shrinks to the tolerance."""
    jump = 0.123456789
    f = lambda x: 1.0 if x > jump else -2.0  # noqa: E731
    fun, _ = _evaluations(f)
    x = _root(fun, 0.0, 1.0, -2.0, 1.0, 1e-10, many)
    assert abs(x - jump) <= 1e-10 + RTOL * abs(x)


@settings(max_examples=60, deadline=None)
@given(st.floats(-0.9, 0.9), st.floats(0.05, 5.0), st.floats(-3.0, 3.0),
       st.sampled_from([1, 8]))
def test_root_of_a_cubic_with_one_sign_change(r, a, c, many):
    """f(x) = (x − r)(a + (x − c)²) has its one real root at r in [−1, 1] (a > 0)."""
    f = lambda x: (x - r) * (a + (x - c) ** 2)  # noqa: E731
    fun, _ = _evaluations(f)
    x = _root(fun, -1.0, 1.0, f(-1.0), f(1.0), 1e-11, many)
    assert abs(x - r) <= 1e-11 + RTOL * abs(x)


def test_motion_update_says_where_else_the_parameter_enters():
    spec = _spec(CASES / "whipple_bicycle.toml")
    model = spec.build(None)
    for name, where in (("w", "bodies[3].com[0]"), ("g", "gravity[2]")):
        assert MotionUpdate(spec.data, None, {}, name, model).reason == f"{name} enters {where}"
    update = MotionUpdate(spec.data, None, {}, "v", model)
    assert update.reason is None
    for p in (0.5, 3.0, 7.25):  # the lean motion equals the reader's
        assert update.motion(repr(p)) == read_motion(spec.data, update.parameters(repr(p)))


def test_batched_pencils_against_qz():
    """solve_descriptor_batch against the QZ path (solve_descriptor) on random pencils: matched
    eigenvalues within the sum of the two first-order bounds (10 κη each, as the modes state
    them); a defective pencil and an ill-conditioned E are not covered, with the reason."""
    from mbseig.eigen.batch import solve_descriptor_batch
    from mbseig.eigen.descriptor import solve_descriptor

    rng = np.random.default_rng(11)
    B, k = 20, 6
    E = rng.standard_normal((B, k, k)) + 4 * np.eye(k)
    A = rng.standard_normal((B, k, k))
    A[-2] = np.diag([1.0, 1.0, 2.0, 3.0, 4.0, 5.0]) + np.diag([1.0, 0, 0, 0, 0], 1)  # Jordan
    E[-2] = np.eye(k)
    E[-1] = np.diag([1.0, 1.0, 1.0, 1.0, 1.0, 1e-12])                                # cond 1e12
    got = solve_descriptor_batch(E, A)
    assert got["reason"][-1] == "E is not well conditioned"
    assert got["reason"][-2] != ""
    for b in range(B - 2):
        assert got["reason"][b] == ""
        ref = solve_descriptor(E[b], A[b])
        bound_b = 10 * got["kappa"][b] * got["eta"][b] * np.maximum(np.abs(got["s"][b]), 1)
        bound_r = 10 * ref.condition * ref.backward_error * np.maximum(np.abs(ref.eigenvalues), 1)
        for s, t in zip(got["s"][b], bound_b, strict=True):
            j = np.argmin(np.abs(ref.eigenvalues - s))
            assert abs(ref.eigenvalues[j] - s) <= t + bound_r[j]


def test_a_model_with_forces_in_the_batch(tmp_path, monkeypatch):
    """The bicycle with a steering damper and spring (a torsional element on the steer joint):
    the batch evaluates the model's own forces at each point's velocities; its sweep equals
    the one-point path's (the tolerances of the module docstring)."""
    text = (CASES / "whipple_bicycle.toml").read_text()
    extra = ('\n[[forces]]\nname = "steer damper"\ntype = "torsional"\njoint = "steer"\n'
             'stiffness = 2.0\ndamping = 0.4\n')
    path = tmp_path / "bicycle_damped.toml"
    path.write_text(text[:text.index("[expected]")] + extra)  # (its expectations are the
    # undamped bicycle's)
    spec = read_case(path)
    assert spec.build(None).forces
    grid = np.linspace(0.5, 10.0, 24)
    xtol = 1e-11
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        a = steady_sweep(spec, "v", grid, jobs=1, progress=False, xtol=xtol)
        monkeypatch.setattr(sweep_module, "BATCH_STEADY", False)
        b = steady_sweep(spec, "v", grid, jobs=1, progress=False, xtol=xtol)
    assert a.batch is None
    assert [p["verdict"] for p in a.points] == [p["verdict"] for p in b.points]
    assert len(a.boundaries) == len(b.boundaries) >= 1
    for x, y in zip(a.boundaries, b.boundaries, strict=True):
        assert (x["kind"], x["stability"]) == (y["kind"], y["stability"])
        assert abs(x["value"] - y["value"]) <= 2 * (xtol + RTOL * abs(y["value"]))


@pytest.mark.parametrize("path,name,grid", LINES, ids=[p.stem for p, _, _ in LINES])
def test_one_point_is_the_sweeps_path_with_a_batch_of_one(path, name, grid):
    """analyze_steady (solver "auto") is the sweep's batch with one motion: each sweep point's
    eigenvalues within twice the one-point analysis's stated bound (each computed eigenvalue
    lies within its own bound; the sweep point's bound, which its JSON does not carry, is the
    same formula on inputs equal to rounding), the same verdict; "descriptor-qz" asks for the
    QZ path."""
    spec = _spec(path)
    sub = grid[::3]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sw = steady_sweep(spec, name, sub, jobs=1, progress=False)
        for p, pt in zip(sub, sw.points, strict=True):
            a = analyze_steady(spec, params={name: repr(float(p))})
            assert a.solution.solver == "descriptor-eig"
            assert pt["verdict"] == a.verdict
            tol = {complex(*r["eigenvalue"]): r["tolerance"] for r in a.modes
                   if not r["rigid_body"]}  # (the sweep lists the pencil's, not the declared)
            for s in (complex(*x) for x in pt["eigenvalues"]):
                near = min(tol, key=lambda z, s=s: min(abs(z - s), abs(z.conjugate() - s)))
                assert min(abs(near - s), abs(near.conjugate() - s)) <= 2 * tol[near]
        qz = analyze_steady(spec, params={name: repr(float(sub[0]))}, solver="descriptor-qz")
    assert qz.solution.solver == "descriptor-qz"


def test_a_batch_that_raises_leaves_each_point_to_the_one_point_path(monkeypatch):
    """An element's error inside the batch (here raised on purpose) does not end the sweep: each
    point is analysed alone and gets that path's result (or its own located error)."""
    from mbseig.errors import EquilibriumError

    def boom(self, motions, **kw):
        raise EquilibriumError("direction of zero length: angle undefined", element="x")

    spec = _spec(CASES / "rolling_disk.toml")
    monkeypatch.setattr(SteadyStack, "analyse", boom)
    monkeypatch.setattr(sweep_module, "_LINES", {})
    line = sweep_module.SteadyLine(spec, None, {}, "v", 1.0)
    for p, got in zip([1.0, 2.5], line.points([1.0, 2.5]), strict=True):
        own = analyze_steady(spec, params={"v": repr(p)}, solver="descriptor-qz")
        assert got.verdict == own.verdict
        assert np.array_equal(got.eigenvalues, own.solution.eigenvalues)
