"""Sweeps by continuation: each line of a sweep follows one equilibrium branch
(docs/design.md, "Equilibrium": continuation in sweeps).

:func:`sweep_line` is the pure function a runner sends to a worker for one line of a sweep (the
first axis varying, the others fixed).  It

1. solves the first point from the case's positions (:func:`mbseig.equilibrium`: position
   solve, trust region, load continuation when needed);
2. follows the branch through the grid (:func:`mbseig.statics.continuation.follow`): tangent
   predictor from the previous equilibrium, pseudo-arclength through folds, branch points
   located, a switch to the stable branch where the followed one loses static stability, a
   fresh solve past a fold that does not turn forward again;
3. at every grid point: the equilibrium record, the linear model and all 2n eigenpairs with
   their stability tolerances (the same classification as ``mbseig modes``), the joints
   outside their range of motion; a grid point the branch did not reach is solved on its own
   (``statics = "cold"``);
4. for the bifurcation diagram: every branch point with its named angles (``[report]``) or
   coordinates and its stability (static, and modal for small models).

The family p ↦ model(p) builds the case once and, where the swept parameter enters only force
scalars, updates those at each value (:class:`~mbseig.casefile.element_readers.ScalarUpdate`:
equal to a build field by field), else builds the case at each value (``record["model"]``).
Inverse-statics commands are resolved at each value, unless resolving them at two values gave
bitwise-equal settings (the swept parameter does not enter them, as a follower load does not
enter a held position command): then the settings are reused; or the swept parameter enters
only the commanded spring's stiffness: then the spring's tension at the commanded posture is
held (:func:`mbseig.statics.inverse.held_tension`, checked at every value; ``record["commands"]``).
``lean=False`` builds and resolves every value (the general path, for comparison).
"""

from __future__ import annotations

import numpy as np

from ..casefile.element_readers import ScalarUpdate
from ..eigen import Problem, Request, solve
from ..errors import MbseigError
from ..linear import linearize
from ..modal import stability, tolerances, worst
from ..model import Model
from ..model.linear_case import LinearCase
from ..statics import equilibrium, examine, resolve
from ..statics.cache import Memo
from ..statics.continuation import CTOL, Family, follow
from ..statics.inverse import command_settings, held_tension, reuse_commands
from ..statics.newton import settings_for
from ..statics.reactions import posture
from ..statics.result import finish
from ..statics.solve import solve_statics
from ..statics.stiffness import static_stability
from .records import SweepPoint

__all__ = ["sweep_line", "family_maker", "modal_point", "DIAGRAM_MODES_MAX"]

DIAGRAM_MODES_MAX = 60  # DOF up to which every branch point of the diagram gets its modal verdict


def family_maker(spec, config, params, axis, *, lean=True):
    """(make, state): make(p) is the model at axis = p with its commands resolved.

    The case is built once; where the swept parameter enters only force scalars (a spring
    constant, a damping value, a load's magnitude) the next values update those
    (:class:`~mbseig.casefile.element_readers.ScalarUpdate`, equal to a build element by
    element), elsewhere every value is built (``state["model"]`` says which and why)."""
    state = {"first": None, "reuse": None, "checked": False, "last": None, "presolve": {},
             "lean": None, "model": None, "held": 0, "resolved": 0, "made": {},
             "held_cache": {}}
    lean_models = lean_commands = bool(lean)

    def build(p):
        lean = state["lean"]
        if lean is not None and lean_models:
            try:
                m = lean.make(p)
            except MbseigError:  # a bad value: the build names the file and the element
                m = None
            if m is not None:
                return m
        m = spec.build(config, **{**params, axis: float(p)})
        if state["model"] is None:
            state["lean"] = lean = (ScalarUpdate(spec.data, config, params, axis, m)
                                    if isinstance(m, Model) else None)
            state["model"] = ("built at every value" if lean is None or not lean_models else
                              f"built at every value ({lean.reason})" if lean.reason else
                              "built once, force scalars updated at each value")
        return m

    def make(p):
        key = float(p)
        if key in state["made"]:  # the same value again (the first point, asked by the family)
            return state["made"][key]
        m = made(p)
        if len(state["made"]) >= 4:
            state["made"].pop(next(iter(state["made"])))
        state["made"][key] = m
        return m

    def made(p):
        m = build(p)
        if not getattr(m, "commands", ()):
            return m
        if state["reuse"] is not None:
            r = reuse_commands(m, state["reuse"])
            if r is not None:
                return r
        if state["checked"] and lean_commands:
            r = held_tension(m, state["last"], cache=state["held_cache"])
            if r is not None:
                state["held"] += 1
                return r
        r = resolve(m, hint=state["last"], cache=state["presolve"])  # from the previous point
        state["last"] = r
        state["resolved"] += 1
        if state["first"] is None:
            state["first"] = (float(p), r)
        elif not state["checked"] and float(p) != state["first"][0]:
            state["checked"] = True
            if command_settings(r) == command_settings(state["first"][1]):
                state["reuse"] = r
        return r

    return make, state


def modal_point(model, eq, params, *, safety, stability_rtol, postures=posture, **fields):
    """The sweep's record of one point: all eigenpairs, their tolerances, the verdict.
    postures(model, q): :func:`mbseig.statics.reactions.posture` (or a kept copy of its
    result); fields: more fields of the :class:`SweepPoint` (how the statics reached it)."""
    lin = linearize(model, eq, signals=False)  # a sweep point uses the modes alone
    if lin.M.shape[0] == 0:  # no degree of freedom (a driven mechanism): no modes
        s, X, tol, verdict, solver = (np.zeros(0, complex), np.zeros((model.n, 0), complex),
                                      np.zeros(0), "stable", "none (no degree of freedom)")
    else:
        sol = solve(Problem(lin.M, lin.P, lin.Q), Request())
        s, solver = sol.eigenvalues, sol.solver
        _, _, tol, rigid = tolerances(sol, safety=safety, stability_rtol=stability_rtol)
        X = lin.N @ sol.vectors
        X = X / np.maximum(np.linalg.norm(X, axis=0), np.finfo(float).tiny)
        verdict = worst(stability(-s.real, tol, rigid))
    out_of_range = ([p["name"] for p in postures(model, eq.q) if not p["in_range"]]
                    if (getattr(model, "report", None) or {}).get("angles") else [])
    return SweepPoint(params=dict(params), error=None, eigenvalues=s, shapes=X, tol=tol,
                      verdict=verdict, out_of_range=out_of_range, solver=solver,
                      q=np.asarray(eq.q, float), iterations=int(eq.iterations),
                      static=(eq.static or {}).get("verdict"), **fields)


def _angles(model, q, postures=posture):
    return ({p["name"]: p["angle_deg"] for p in postures(model, q)} if model.report.get("angles")
            else {})


def _kept_postures():
    """posture(model, q) computed once per model and q (a grid point's record and its point of
    the bifurcation diagram ask for the same)."""
    kept = {}

    def postures(model, q):
        key = (id(model), np.asarray(q, float).tobytes())
        hit = kept.get(key)
        if hit is None or hit[0] is not model:
            hit = kept[key] = (model, posture(model, q))
        return hit[1]

    return postures


def sweep_line(case, config, params, axis, values, *, safety=10.0, stability_rtol=1e-12,
               switch=True, lean=True):
    """One line of a sweep by continuation (module docstring); a pure, picklable function.

    Returns {"points": [point dicts as :func:`mbseig.studies.sweep.evaluate_point`, with
    ``statics`` = "continuation" | "cold"], "branch": [diagram points], "events": [folds,
    branch points, switches, jumps], "record": {...}} or, when the first point fails,
    {"error": message}.
    """
    values = np.asarray(values, dtype=float)
    make, state = family_maker(case, config, params, axis, lean=lean)
    opts = {"safety": safety, "stability_rtol": stability_rtol}
    postures = _kept_postures()

    def point_params(p):
        return {**params, axis: float(p)}

    try:
        model0 = make(values[0])
        if isinstance(model0, LinearCase):  # matrices only: no equilibrium to follow
            return {"error": "a linear case has no equilibrium branch", "points": None}
        eq0 = equilibrium(model0, offer_stable=False, self_stress="report")
    except MbseigError as exc:
        return {"error": exc.one_line(), "points": None}
    fam = Family(make, abs(float(values[-1] - values[0])) or 1.0, eq0.model, eq0.q)

    def static_verdict(model, q, lam):
        return static_stability(model, q, lam)["verdict"]

    def restart(p, q_start):
        return solve_statics(make(p), q_init=q_start).q

    try:
        branch = follow(fam, values, fam.start(eq0.q, values[0]), stability=static_verdict,
                        restart=restart, switch=switch)
    except MbseigError as exc:
        branch = None
        failure = exc.one_line()
    points = []
    for k, v in enumerate(values):
        bp = branch.grid[k] if branch is not None else None
        try:
            model = fam.model(v)
            if bp is not None:  # converged by the continuation's corrector: the record only
                q = bp.y[:fam.n]
                # g, Φ, Φ_q at q evaluated once (by the corrector) for the scale and the record
                memo = Memo(model, q=q, known=fam.known(v, q))
                st = settings_for(memo, q, tol=1e-12, xtol=None, floor_tol=1e-8, max_iter=50,
                                  rank_tol=1e-10)
                eq = finish(model, q, st, iterations=bp.iterations, correction=CTOL,
                            method="continuation", path={"start": "branch", "kind": bp.kind,
                                                         "segment": bp.segment}, memo=memo)
                how = "continuation"
            else:
                eq = equilibrium(model, offer_stable=False, self_stress="report")
                how = "cold"
            eq = examine(eq, offer_stable=False, self_stress="report")
            where = ({} if bp is None else
                     {"segment": bp.segment, "branch_kind": bp.kind,
                      "corrector_iterations": bp.iterations})
            pt = modal_point(eq.model, eq, point_params(v), **opts, postures=postures,
                             statics=how, **where)
        except MbseigError as exc:
            pt = SweepPoint.failed(point_params(v), exc.one_line())
        points.append(pt)
    out = {"points": points, "branch": [], "events": [], "record": {}}
    if branch is None:
        out["record"] = {"continuation": f"failed: {failure}"}
        return out
    diagram = []
    grid_verdict = {id(bp): points[k].get("verdict") for k, bp in enumerate(branch.grid)
                    if bp is not None}
    # between two grid points of one segment with the same verdict, the branch has it too;
    # elsewhere (and at folds and branch points) the modes decide, for small models
    order = [grid_verdict.get(id(bp)) for bp in branch.points]
    for i, bp in enumerate(branch.points):
        if order[i] is not None or bp.kind in ("fold", "branch point"):
            continue
        prev = next((order[j] for j in range(i - 1, -1, -1) if order[j] is not None
                     and branch.points[j].segment == bp.segment), None)
        nxt = next((order[j] for j in range(i + 1, len(order)) if order[j] is not None
                    and branch.points[j].segment == bp.segment), None)
        if prev is not None and prev == nxt and grid_verdict.get(id(bp)) is None:
            grid_verdict[id(bp)] = prev
    # a grid point's static verdict was judged by examine() on the same equilibrium; with
    # every constraint row followed, its multipliers are the same (unique), so it is reused
    grid_static = ({id(bp): points[k].get("static") for k, bp in enumerate(branch.grid)
                    if bp is not None and points[k].get("static") in ("stable", "unstable", "neutral")}
                   if fam.rows.size == fam.m else {})
    for bp in branch.points:
        model = fam.model(bp.p)
        q = bp.y[:fam.n]
        lam = fam.lam_full(bp.y)
        rec = {"p": bp.p, "kind": bp.kind, "segment": bp.segment,
               "q": [float(x) for x in q] if fam.n <= 500 else None,
               "angles": _angles(model, q, postures), "pdot": bp.pdot}
        rec["static"] = grid_static.get(id(bp))
        if rec["static"] is None:
            try:
                rec["static"] = static_verdict(model, q, lam)
            except (MbseigError, ValueError, np.linalg.LinAlgError):
                rec["static"] = None
        rec["verdict"] = grid_verdict.get(id(bp))
        if rec["verdict"] is None and fam.n - fam.rows.size <= DIAGRAM_MODES_MAX:
            try:
                eq = solve_statics(model, q_init=q, continuation=False)
                rec["verdict"] = modal_point(model, eq, point_params(bp.p), **opts)["verdict"]
            except MbseigError:
                pass
        diagram.append(rec)
    events = []
    for ev in branch.events:
        e = {k: v for k, v in ev.items() if k != "point"}
        if "point" in ev:
            i = ev["point"]
            before = next((diagram[j] for j in range(i - 1, -1, -1)
                           if diagram[j]["segment"] == diagram[i]["segment"]
                           and diagram[j]["kind"] not in ("fold", "branch point")), None)
            after = next((diagram[j] for j in range(i + 1, len(diagram))
                          if diagram[j]["segment"] == diagram[i]["segment"]
                          and diagram[j]["kind"] not in ("fold", "branch point")), None)
            e["before"] = None if before is None else (before["verdict"] or before["static"])
            e["after"] = None if after is None else (after["verdict"] or after["static"])
            e["dof"] = int(fam.n - fam.rows.size)
            e["angles"] = diagram[i]["angles"]
        events.append(e)
    commands = ("reused (the swept parameter does not enter them)" if state["reuse"] is not None
                else f"resolved at {state['resolved']} values, the spring's tension held at "
                     f"{state['held']}" if state["held"] else "resolved at every value")
    out.update(branch=diagram, events=events,
               record={**branch.record, "model": state["model"], "commands": commands})
    return out
