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
scalars of a planar case, updates those at each value
(:class:`~mbseig.casefile.element_readers.ScalarUpdate`: equal to a build field by field), where
it enters only bodies' masses and inertias of a spatial case, forms the mass matrix and the
gravity load again from the bodies' parts (:class:`~mbseig.casefile.element_readers.MassUpdate`:
equal to a build bit for bit), else builds the case at each value (``record["model"]``).
Inverse-statics commands are resolved at each value, unless resolving them at two values gave
bitwise-equal settings (the swept parameter does not enter them, as a follower load does not
enter a held position command): then the settings are reused; or the swept parameter enters
only the commanded spring's stiffness: then the spring's tension at the commanded posture is
held (:func:`mbseig.statics.inverse.held_tension`, checked at every value; ``record["commands"]``).
``lean=False`` builds and resolves every value (the general path, for comparison).  The lines of
one sweep that differ only in damping values share one line's statics (:func:`_shared_statics`).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from ..casefile.element_readers import MassUpdate, ScalarUpdate
from ..errors import MbseigError
from ..linear import linearize
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
from .batch_line import batch_line
from .records import SweepPoint
from .spectra import point_spectra

__all__ = ["sweep_line", "family_maker", "modal_point", "linear_point", "point_record", "release",
           "DIAGRAM_MODES_MAX"]

DIAGRAM_MODES_MAX = 60  # DOF up to which every branch point of the diagram gets its modal verdict

_SHARED: dict = {}  # the last lines whose statics later lines of their sweep may share

#: solve a line's grid points together where the batch can (:mod:`mbseig.studies.batch_line`);
#: False follows every line point by point (the continuation alone: its tests, comparisons)
BATCH_LINES = True


def _assigned(axis, p) -> dict:
    """{name: value} of the swept parameter(s) ``axis`` at ``p`` (a tuple of names takes a
    tuple of values)."""
    if isinstance(axis, tuple):
        return {a: float(v) for a, v in zip(axis, p, strict=True)}
    return {axis: float(p)}


def _value_key(p):
    """A value of the swept parameter(s) as a key: a float, or a tuple of floats."""
    return tuple(float(v) for v in p) if isinstance(p, tuple) else float(p)


def family_maker(spec, config, params, axis, *, lean=True):
    """(make, state): make(p) is the model at axis = p with its commands resolved.

    The case is built once; where the swept parameter enters only force scalars (a spring
    constant, a damping value, a load's magnitude) the next values update those
    (:class:`~mbseig.casefile.element_readers.ScalarUpdate`, equal to a build element by
    element), elsewhere every value is built (``state["model"]`` says which and why).

    ``axis`` may be a tuple of parameter names moved together (``p`` a tuple of their values,
    in that order: the samples of :mod:`mbseig.studies.uncertainty`)."""
    state = {"first": None, "reuse": None, "checked": False, "last": None, "presolve": {},
             "lean": None, "model": None, "held": 0, "resolved": 0, "made": {},
             "held_cache": {}, "kept": None, "donor": None}
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
        m = spec.build(config, **{**params, **_assigned(axis, p)})
        if state["model"] is None:
            kind = MassUpdate if (spec.data.get("dimension") == 3) else ScalarUpdate
            state["lean"] = lean = (kind(spec.data, config, params, axis, m)
                                    if isinstance(m, Model) else None)
            what = ("body masses and inertias" if kind is MassUpdate else "force scalars")
            state["model"] = ("built at every value" if lean is None or not lean_models else
                              f"built at every value ({lean.reason})" if lean.reason else
                              f"built once, {what} updated at each value")
        return m

    def make(p):
        key = _value_key(p)
        if key in state["made"]:  # the same value again (the first point, asked by the family)
            return state["made"][key]
        m = made(p)
        if state["kept"] is not None:  # every model of the line, for the lines that share it
            state["kept"][key] = m
        if len(state["made"]) >= 4:
            state["made"].pop(next(iter(state["made"])))
        state["made"][key] = m
        return m

    def made(p):
        m = build(p)
        if not getattr(m, "commands", ()):
            return m
        donor = (state["donor"] or {}).get(_value_key(p))
        if donor is not None:  # the line whose statics this one shares (_shared_statics)
            r = reuse_commands(m, donor)
            if r is not None:
                return r
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
            state["first"] = (_value_key(p), r)
        elif not state["checked"] and _value_key(p) != state["first"][0]:
            state["checked"] = True
            if command_settings(r) == command_settings(state["first"][1]):
                state["reuse"] = r
        return r

    def make_many(values):
        """make(p) of every value, the models of a MassUpdate formed together (None where
        make(p) must form them one at a time)."""
        lean = state["lean"]
        if not (lean_models and isinstance(lean, MassUpdate) and lean.reason is None):
            return None
        try:
            got = lean.make_many([_value_key(v) for v in values])
        except MbseigError:  # a bad value: each alone (the build names the file and element)
            return None
        if state["kept"] is not None:
            for v, m in zip(values, got, strict=True):
                state["kept"][_value_key(v)] = m
        return got

    make.many = make_many
    state["build"] = build
    return make, state


def linear_point(model, eq, *, basis=None, kept=None):
    """The linear model of a sweep point (the modes alone: no signals); basis: the null-space
    basis of this equilibrium when known, kept: a list the linearization's basis is appended
    to."""
    lin = linearize(model, eq, signals=False, basis=basis)
    if kept is not None and isinstance(lin.N, np.ndarray):
        kept.append((lin.N, lin.rank, lin.independent, lin.tolerances.get("basis_min_cosine")))
    return lin


def point_record(model, eq, params, spectrum, *, postures=posture, **fields):
    """The :class:`SweepPoint` of one point from its equilibrium and its
    :class:`~mbseig.studies.spectra.PointSpectrum`; fields: how the statics reached it."""
    out_of_range = ([p["name"] for p in postures(model, eq.q) if not p["in_range"]]
                    if (getattr(model, "report", None) or {}).get("angles") else [])
    return SweepPoint(params=dict(params), error=None, eigenvalues=spectrum.eigenvalues,
                      shapes=spectrum.shapes, tol=spectrum.tol, verdict=spectrum.verdict,
                      out_of_range=out_of_range, solver=spectrum.solver,
                      q=np.asarray(eq.q, float), iterations=int(eq.iterations),
                      static=(eq.static or {}).get("verdict"), **fields)


def modal_point(model, eq, params, *, safety, stability_rtol, postures=posture, basis=None,
                kept=None, **fields):
    """The sweep's record of one point: all eigenpairs, their tolerances, the verdict; the
    modes stage of a line (:func:`~mbseig.studies.spectra.point_spectra`) with a batch of one.
    postures(model, q): :func:`mbseig.statics.reactions.posture` (or a kept copy of its
    result); basis, kept: :func:`linear_point`; fields: more fields of the
    :class:`SweepPoint` (how the statics reached it)."""
    lin = linear_point(model, eq, basis=basis, kept=kept)
    spectrum = point_spectra([lin], safety=safety, stability_rtol=stability_rtol)[0]
    if isinstance(spectrum, BaseException):
        raise spectrum
    return point_record(model, eq, params, spectrum, postures=postures, **fields)


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
               switch=True, lean=True, share=None):
    """One line of a sweep by continuation (module docstring); a pure, picklable function.

    Returns {"points": [point dicts as :func:`mbseig.studies.sweep.evaluate_point`, with
    ``statics`` = "continuation" | "batch" | "cold"], "branch": [diagram points], "events": [folds,
    branch points, switches, jumps], "record": {...}} or, when the first point fails,
    {"error": message}.

    share : a token of one sweep (:func:`mbseig.studies.sweep.run_sweep`): a line of it whose
        parameters differ from an earlier line's of the same process only in ones that enter
        damping values alone takes that line's statics (:func:`_shared_statics`); not with
        ``lean=False`` (every value built and resolved).
    """
    values = np.asarray(values, dtype=float)
    make, state = family_maker(case, config, params, axis, lean=lean)
    opts = {"safety": safety, "stability_rtol": stability_rtol}
    postures = _kept_postures()
    key = None if share is None or not lean else (share, id(case), config, axis, values.tobytes(),
                                      bool(lean), bool(switch), tuple(sorted(params)))
    shared = _shared_statics(key, case, config, params, axis, values, state)

    def point_params(p):
        return {**params, axis: float(p)}

    why_not = None
    if shared is None:
        if key is not None:
            state["kept"] = {}
        try:
            model0 = make(values[0])
            if isinstance(model0, LinearCase):  # matrices only: no equilibrium to follow
                return {"error": "a linear case has no equilibrium branch", "points": None}
            eq0 = equilibrium(model0, offer_stable=False, self_stress="report")
        except MbseigError as exc:
            return {"error": exc.one_line(), "points": None}
        fam = Family(make, abs(float(values[-1] - values[0])) or 1.0, eq0.model, eq0.q)

        def restart(p, q_start):
            return solve_statics(make(p), q_init=q_start).q

        batched = (None, None, None)
        if BATCH_LINES and len(values) > 1:
            try:
                batched = batch_line(fam, values, eq0)
            except MbseigError as exc:  # an element refused a point: followed point by point
                batched = (None, None, exc.one_line())
            except (np.linalg.LinAlgError, ValueError, FloatingPointError) as exc:
                batched = (None, None, f"{type(exc).__name__}: {exc}")
        why_not = batched[2] if batched[0] is None else None
        if batched[0] is not None:
            return _batched_line(batched, values, point_params, opts, postures, state)
        try:
            branch = follow(fam, values, fam.start(eq0.q, values[0]), stability=_static_verdict,
                            restart=restart, switch=switch)
        except MbseigError as exc:
            branch = None
            failure = exc.one_line()
        model_at, grid = fam.model, []
    else:
        fam, branch, model_at = shared["fam"], shared["branch"], make
    # the statics and linear model of every grid point, then the modes of all of them at once
    staged = []
    for k, v in enumerate(values):
        kept = []
        try:
            if shared is None:
                eq, how, where = _grid_statics(fam, branch, k, v)
                grid.append((eq, how, where, kept))
            else:  # the same equilibrium record (and null-space basis), of this line's model
                eq, how, where, kept = shared["grid"][k]
                eq = dataclasses.replace(eq, model=make(v), q=eq.q.copy(), lam=eq.lam.copy())
            lin = linear_point(eq.model, eq, basis=kept[0] if shared and kept else None,
                               kept=None if shared else kept)
            staged.append((eq, {"statics": how, **where}, lin))
        except MbseigError as exc:
            staged.append((None, None, exc))
    spectra = point_spectra([lin for _, _, lin in staged], **opts)
    points = []
    for v, (eq, fields, _), spectrum in zip(values, staged, spectra, strict=True):
        if isinstance(spectrum, MbseigError):
            points.append(SweepPoint.failed(point_params(v), spectrum.one_line()))
        else:
            points.append(point_record(eq.model, eq, point_params(v), spectrum,
                                       postures=postures, **fields))
    out = {"points": points, "branch": [], "events": [], "record": {}}
    if branch is None:
        out["record"] = {"continuation": f"failed: {failure}"}
        return out
    commands = shared["commands"] if shared is not None else (
        "reused (the swept parameter does not enter them)" if state["reuse"] is not None
        else f"resolved at {state['resolved']} values, the spring's tension held at "
             f"{state['held']}" if state["held"] else "resolved at every value")
    if shared is None and key is not None and len(grid) == len(values) and all(
            how == "continuation" and eq.static.get("verdict") != "unstable"
            and pt.get("error") is None for (eq, how, _, _), pt in zip(grid, points, strict=True)):
        for old in list(_SHARED)[:-1]:  # (the lines of one sweep follow each other)
            _SHARED.pop(old, None)
        _SHARED[key] = {"case": case, "params": dict(params), "fam": fam, "branch": branch,
                        "grid": grid, "commands": commands, "models": state["kept"]}
    diagram, events = _diagram(fam, branch, points, model_at, point_params, opts, postures)
    out.update(branch=diagram, events=events,
               record={**branch.record, "model": state["model"], "commands": commands,
                       **({"batch": f"declined: {why_not}"} if why_not else {})})
    return out


def _batched_line(batched, values, point_params, opts, postures, state):
    """The line's result from :func:`mbseig.studies.batch_line.batch_line`: every grid point's
    record from the batched equilibria and linear models, the modes of all at once; the branch
    is the grid itself (no fold or branch point lies on it: the batch checked that)."""
    eqs, lins, record = batched
    kinds = ["start"] + ["grid"] * (len(values) - 1)  # as the continuation names its points
    points = batched_points(eqs, lins, values, point_params, opts, postures, kinds)
    diagram = [{"p": float(v), "kind": kind, "segment": 0,
                "q": [float(x) for x in eq.q] if eq.q.size <= 500 else None,
                "angles": _angles(eq.model, eq.q, postures),
                "pdot": None,  # (no tangent is formed on a batched line)
                "static": pt.get("static"), "verdict": pt.get("verdict")}
               for v, eq, pt, kind in zip(values, eqs, points, kinds, strict=True)]
    commands = ("reused (the swept parameter does not enter them)" if state["reuse"] is not None
                else f"resolved at {state['resolved']} values, the spring's tension held at "
                     f"{state['held']}" if state["held"] else "resolved at every value")
    return {"points": points, "branch": diagram, "events": [],
            "record": {**record, "model": state["model"], "commands": commands}}


def batched_points(eqs, lins, values, point_params, opts, postures, kinds):
    """The point records of equilibria and linear models solved together
    (:func:`~mbseig.studies.batch_line.batch_line`), their modes at once
    (:func:`~mbseig.studies.spectra.point_spectra`); a point whose modes fail gets its error."""
    spectra = point_spectra(lins, **opts)
    points = []
    for v, eq, spectrum, kind in zip(values, eqs, spectra, kinds, strict=True):
        if isinstance(spectrum, MbseigError):
            points.append(SweepPoint.failed(point_params(v), spectrum.one_line()))
            continue
        points.append(point_record(eq.model, eq, point_params(v), spectrum, postures=postures,
                                   statics="batch", segment=0, branch_kind=kind,
                                   corrector_iterations=int(eq.iterations)))
    return points


def _static_verdict(model, q, lam):
    return static_stability(model, q, lam)["verdict"]


def _grid_statics(fam, branch, k, v):
    """(equilibrium record, how, where) of grid point k: the corrector's equilibrium, or a
    solve of its own where the branch did not reach it."""
    bp = branch.grid[k] if branch is not None else None
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
             {"segment": bp.segment, "branch_kind": bp.kind, "corrector_iterations": bp.iterations})
    return eq, how, where


def _shared_statics(key, case, config, params, axis, values, state):
    """The statics of an earlier line of the same sweep (``key``) when this line's parameters
    differ from its only in ones that enter nothing but damping values of force elements
    (:class:`~mbseig.casefile.element_readers.ScalarUpdate` of each, with ``damping`` its only
    field): at rest (q̇ = 0) a damping value multiplies a zero rate, so the forces, their
    stiffness, the commands, the branch and every equilibrium record are those of that line.
    This line's models take that line's command settings (:func:`reuse_commands`); its modes
    are its own.  None (follow the line) otherwise."""
    donor = None if key is None else _SHARED.get(key)
    if donor is None or donor["case"] is not case:
        return None
    names = [k for k in params if not _same(params[k], donor["params"][k])]
    if not names:
        return None  # (the same line again: followed again)
    try:
        model0 = state["build"](values[0])
        for name in names:
            su = ScalarUpdate(case.data, config, {**params, axis: float(values[0])}, name, model0)
            if su.reason is not None or any(f != "damping"
                                            for *_, keys in su.updates for f in keys):
                return None
    except (MbseigError, KeyError, TypeError, ValueError):
        return None
    state["donor"] = donor["models"]
    return donor


def release(share):
    """Drop the statics the lines of the sweep ``share`` kept for each other (its end)."""
    for key in [k for k in list(_SHARED) if k[0] == share]:
        _SHARED.pop(key, None)


def _same(a, b) -> bool:
    try:
        return type(a) is type(b) and bool(a == b)
    except (TypeError, ValueError):
        return False


def _diagram(fam, branch, points, model_at, point_params, opts, postures):
    """The bifurcation diagram's points (every branch point with its angles, static and modal
    verdicts) and the branch's events with the verdicts on either side."""
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
                    if bp is not None
                    and points[k].get("static") in ("stable", "unstable", "neutral")}
                   if fam.rows.size == fam.m else {})
    for bp in branch.points:
        model = model_at(bp.p)
        q = bp.y[:fam.n]
        lam = fam.lam_full(bp.y)
        rec = {"p": bp.p, "kind": bp.kind, "segment": bp.segment,
               "q": [float(x) for x in q] if fam.n <= 500 else None,
               "angles": _angles(model, q, postures), "pdot": bp.pdot}
        rec["static"] = grid_static.get(id(bp))
        if rec["static"] is None:
            try:
                rec["static"] = _static_verdict(model, q, lam)
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
    return diagram, events
