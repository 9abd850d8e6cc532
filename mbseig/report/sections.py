"""The report's section of one configuration: model, equilibrium (posture, range of motion,
inverse statics, actuator, pin reactions, constraint forces), the mode table with the stability
margin and the rule of its tolerance, the mechanism with its mode shapes, the pole map and the
time-domain check; all figures from :mod:`mbseig.plots`, all numbers from the study."""

from __future__ import annotations

import math

import numpy as np

from .. import plots
from .modes import check_table, least_text, mode_label, mode_table, read, scope_blocks
from .text import fmt
from .units import with_unit

__all__ = ["configuration_blocks", "check_blocks", "mode_label", "statics_text", "describe",
           "animation_blocks", "parameter_blocks", "modes_blocks", "pole_blocks",
           "MAX_DRAWN_MODES"]

#: modes drawn (shape figure, animations) at most, per dimension: the lowest, as the table
#: lists them; a beam model lists hundreds (the table has them all), and a 3-D mode takes a row
#: of four views
MAX_DRAWN_MODES = {2: 12, 3: 6}


def configuration_blocks(case, study, out_dir, *, run_check, stem, units, animations=True):
    """Blocks of one configuration (:class:`~mbseig.studies.report_studies.ConfigurationStudy`)."""
    config = None if study.config == "base" else study.config
    a = study.analysis
    model, eq, lin, md = a.model, a.eq, a.linear, a.modes
    tag = config or "base"
    blocks = [("h2", f"Configuration {tag}")]
    blocks.append(("p", f"**{tag}**: " + (describe(case, config) if config else
                                          "the case as written, no configuration applied") + "."))
    blocks.append(("h3", "Model"))
    blocks.append(("table", ["quantity", "value"], [
        ["coordinates", str(model.n)],
        ["constraints", str(model.n_constraints)],
        ["redundant constraints",
         f"{eq.n_redundant}" + (f" ({'; '.join(eq.redundant)})" if eq.redundant else "")],
        ["degrees of freedom", str(lin.dof)],
        ["equilibrium residual", f"{eq.residual:.1e} ({eq.iterations} Newton iterations)"],
        ["eigensolver", f"{md.solver} ({md.solver_reason})"],
    ]))
    blocks += parameter_blocks(case, model, units)
    linear_case, rep = study.linear_case, study.reactions
    if not linear_case:
        blocks.append(("h3", "Equilibrium"))
        blocks.append(("p", statics_text(eq)))
    if rep["posture"]:
        blocks.append(("table",
                       ["joint", "flexion [deg]", "range [deg]", "margin [deg]", "in range"],
                       [[p["name"], fmt(p["angle_deg"], 6),
                         "–" if p["range_deg"] is None
                         else f"{p['range_deg'][0]:g} … {p['range_deg'][1]:g}",
                         fmt(p["margin_deg"], 4), "yes" if p["in_range"] else "**NO**"]
                        for p in rep["posture"]]))
        flags = rep["out_of_range"]
        blocks.append(("p", "Range of motion: " + ("all joints inside." if not flags else
                                                    "OUTSIDE for " + ", ".join(flags) + ".")))
    for d in rep["drivers"]:
        sets = "; ".join(
            f"{s['element']}: " + (f"free length {s['free_length'] * 1e3:.6g} mm, length "
                                   f"{s['length'] * 1e3:.6g} mm, tension {s['tension']:.6g} N"
                                   if "free_length" in s
                                   else f"locked at {s['length'] * 1e3:.6g} mm")
            for s in d["sets"])
        unloaded = d.get("unloaded") or []
        held = (f" The command is set on the device without {', '.join(unloaded)} and held as "
                f"that load changes (a position command)." if unloaded else "")
        blocks.append(("p", f"Inverse statics ({d['driver']}): commanded angle "
                            f"{math.degrees(d['angle_target']):.6g} deg needs an effort of "
                            f"{d['effort']:.6g} {d['effort_unit']}; {sets}.{held}"))
    if rep["actuator"]:
        blocks.append(("table", ["actuator element", "kind", "length [mm]", "tension [N]"],
                       [[r["element"], r["kind"], fmt(r["length"] * 1e3, 6), fmt(r["tension"], 6)]
                        for r in rep["actuator"]]))
    zero = float(getattr(study, "reaction_zero", 0.0) or 0.0)

    def rfmt(x, digits):  # a reaction within its error bound is rounding residue: 0
        return fmt(x, digits, bound=zero)
    if rep["pins"]:
        blocks.append(("table", ["pin (force on the outboard bodies)", "point", "Fx [N]", "Fy [N]",
                                 "|F| [N]"],
                       [[p["name"], p["point"], rfmt(p["force"][0], 5), rfmt(p["force"][1], 5),
                         rfmt(p["magnitude"], 5)] for p in rep["pins"]]))
    rows, wrenches, internal = [], [], []
    for c in rep["constraints"]:
        if c.get("kind") == "internal":  # a spatial body's unit-vector conditions: no joint
            internal.append(c.get("on") or c["element"])
            continue
        if c.get("force") is not None and c.get("moment") is not None:
            wrenches.append(_wrench_row(c, rfmt))
            continue
        r = c["reaction"]
        value = r["value"] if isinstance(r["value"], list) else [r["value"]]
        carried = f"{r['label']} {', '.join(rfmt(x, 5) for x in value)} {r['unit']}".rstrip()
        rows.append([c["element"], ", ".join(fmt(x, 6) for x in c["multipliers"]), carried])
    if wrenches:
        blocks.append(("table", ["joint", "on body", "at [m]", "F global [N]", "M global [N m]",
                                 "F body axes u, v, w [N]", "M body axes [N m]",
                                 "error bound F / M"], wrenches))
        blocks.append(("p", "Force F and moment M on the body named, about the joint point; a "
                            "value within its error bound (from the multipliers' solve: "
                            "residual and σ_min(Φ_q)) is printed as 0. A spatial body's axes "
                            "u, v, w are parallel to global x, y, z at the reference."))
    if rows:
        blocks.append(("table", ["constraint", "multiplier λ (in the constraint's own scaling)",
                                 "reaction"], rows))
    if internal:
        blocks.append(("p", f"Not listed: the unit-vector conditions of {', '.join(internal)} "
                            f"(internal to the body coordinates, no joint force)."))
    if (rows or rep["pins"]) and zero > 0:
        blocks.append(("p", f"Reactions below their error bound ({zero:.2g}: the equilibrium's "
                            f"tolerance times the largest reaction) are rounding residue and "
                            f"printed as 0."))

    listing = study.listing
    blocks += modes_blocks(listing, study.least)
    drawn = min(len(md), MAX_DRAWN_MODES.get(getattr(model, "dimension", 2), 12))
    labels = [mode_label(k, listing) for k in range(drawn)]
    if not linear_case and drawn < len(md):
        blocks.append(("p", f"The figures below draw the lowest {drawn} of the {len(md)} modes "
                            f"(the table lists them all)."))
    if not linear_case:
        if model.dimension == 3:
            fig = spatial_draw()(model, eq.q, md.shapes[:, :drawn], labels,
                                  title=f"{tag}: equilibrium (black) and mode shapes (±, red/blue)")
        else:
            fig = plots.mechanism_modes(
                eq.model if eq.model is not None else model, eq.q, md.shapes[:, :drawn], labels,
                eigenvalues=md.eigenvalues[:drawn], kinds=list(md.kind)[:drawn],
                title=f"{tag}: equilibrium (black) and mode shapes, rigid bodies kept rigid")
        img = plots.save(fig, out_dir / f"{stem}_{tag}_shapes.png")
        blocks.append(("img", img, f"{tag}: mechanism at equilibrium with every element (bodies, "
                                   f"springs, sliders and their guides, torsional springs, loads) "
                                   f"and each mode shape superposed: displaced along the mode and "
                                   f"projected back onto the constraints Φ(q) = 0, so bodies stay "
                                   f"rigid; a real (overdamped) mode is drawn as its decay"))
        if animations:
            blocks += animation_blocks(eq.model if eq.model is not None else model, eq.q, md,
                                       out_dir, f"{stem}_{tag}", count=drawn, listing=listing)
    blocks += pole_blocks(listing, tag, out_dir / f"{stem}_{tag}_poles.png")
    blocks += check_blocks(study.check, run_check, listing)
    return blocks


def parameter_blocks(case, model, units):
    """The parameters with their units (a table), and the derived ones with their expressions."""
    raw = getattr(case, "parameters", {}) or {}
    prow, derived = [], []
    for k, v in model.parameters.items():
        u = units.get(k)
        unit = "–" if u == "1" else (u or "not given in the case")
        if isinstance(raw.get(k), str):
            derived.append(f"{k} = {with_unit(fmt(v, 6), u) if u else fmt(v, 6)} "
                           f"(`{raw[k]}`" + ("" if u else ", unit not given in the case") + ")")
        else:
            prow.append([k, fmt(v, 6), unit])
    blocks = []
    if prow:
        blocks.append(("table", ["parameter", "value", "unit"], prow))
    if derived:
        blocks.append(("p", "Derived parameters: " + "; ".join(derived) + "."))
    return blocks


def modes_blocks(listing, least):
    """The modes subsection's text: heading with the verdict, the mode table with units, the
    verdict's scope, the zero rule's note and the stability margin."""
    return ([("h3", f"Modes — verdict: {listing.verdict}"), mode_table(listing)]
            + scope_blocks(listing) + [("p", least_text(listing, least))])


def pole_blocks(listing, tag, path):
    """The pole map of the listing (values as read: the zero rule), numbered as the table."""
    s = np.array([complex(read(listing, k)["re"], read(listing, k)["im"])
                  for k in range(len(listing))], complex)
    img = plots.save(plots.pole_map(s, title=f"{tag}: pole map", stability=listing.stability),
                     path)
    return [("img", img, f"{tag}: pole map over lines of constant ζ and circles of constant "
                         f"ω_n; numbers are the modes of the table")]


def animation_blocks(model, q0, md, out_dir, prefix, *, listing, frames=12, fps=10, count=None):
    """One looping GIF a listed mode (the lowest ``count``;
    :func:`mbseig.plots.animation.write_mode_gif`), shown side by side."""
    from ..plots.animation import oscillates, write_mode_gif
    items = []
    for k in range(len(md) if count is None else min(len(md), count)):
        path = write_mode_gif(model, q0, md.shapes[:, k], out_dir / f"{prefix}_mode{k + 1}.gif",
                              label=mode_label(k, listing),
                              oscillatory=oscillates(md.kind[k], md.eigenvalues[k]),
                              frames=frames, fps=fps)
        items.append((path, f"mode {k + 1}, animated: one period"))
    if not items:
        return []
    return [("p", "Animated mode shapes (one period each, looping; bodies kept rigid, the "
                  "equilibrium in grey):"), ("gallery", items)]


def spatial_draw():
    """The three-view drawing of spatial models (mbseig.plots.spatial), imported when needed."""
    from ..plots import spatial as plots_spatial

    return plots_spatial.spatial_modes


def statics_text(eq):
    """One paragraph on how the equilibrium was found and whether it is statically stable."""
    tol = eq.tolerances
    path = eq.path or {}
    start = ("the commanded posture of the inverse statics" if getattr(eq.model, "drivers", ())
             else "the case's positions")
    how = {"newton": f"Newton from {start}"}.get(eq.method, eq.method)
    if path.get("load_steps"):
        how += f" ({path['load_steps']} load steps; the direct Newton failed: {path.get('direct')})"
    st = eq.static or {}
    verdict = st.get("verdict")
    stab = {"stable": "statically stable (the reduced tangent stiffness is positive definite)",
            "unstable": f"statically UNSTABLE ({st.get('index')} direction(s) of negative "
                        "stiffness)",
            "neutral": "statically neutral (a zero stiffness)",
            "undetermined": (("statics cannot decide (an eigenvalue of the reduced stiffness "
                              "within its tolerance of zero, so the sign of its determinant is "
                              "undecided): see the modes") if st.get("zero") else
                             ("statics cannot decide (non-symmetric stiffness with an even number "
                              "of negative real eigenvalues): see the modes")),
            "not examined": "not examined (above the dense limit)"}.get(verdict, "–")
    text = (f"Statics: {how}, {eq.iterations} Newton iterations; converged when "
            f"{tol.get('criterion', '')} (tol = {tol.get('tol', 0):g}, xtol = "
            f"{tol.get('xtol', 0):g}); final Newton correction {eq.correction:.2g} of the model's "
            f"size. The equilibrium is {stab}.")
    for note in eq.notes:
        text += f" {note[0].upper() + note[1:]}."
    return text


def describe(case, config):
    return str(case.configurations.get(config, {}).get("description", ""))


def check_blocks(res, run_check, listing):
    blocks = [("h3", "Time-domain check")]
    if not run_check:
        blocks.append(("p", "Time-domain check not run (report built with --no-check)."))
        return blocks
    tol = res.tolerances
    blocks.append(("p", f"Each mode is excited alone in the nonlinear model ({res.integrator}, "
                        f"rtol {tol['ode_rtol']:g}) and its modal coordinate fitted; tolerances: δ "
                        f"{tol['delta_rtol']:g} relative, ω {tol['omega_rtol']:g} relative. "
                        "Result: "
                        f"{'all passed' if res.passed else 'FAILED for ' + str(res.failed)}."))
    blocks.append(check_table(res, listing))
    return blocks


def _wrench_row(c, rfmt):
    """A joint's row of the report's wrench table
    (:func:`mbseig.statics.reactions.reaction_forces`)."""
    def vec(v):
        return "(" + ", ".join(rfmt(x, 5) for x in v) + ")"
    err = c.get("error") or {}
    bound = (f"{max(err.get('force') or [0.0]):.1e} / {max(err.get('moment') or [0.0]):.1e}"
             if err else "")
    return [c["element"], c.get("on") or "", vec(c.get("at") or []), vec(c["force"]),
            vec(c["moment"]), vec(c.get("force_body") or []), vec(c.get("moment_body") or []),
            bound]

