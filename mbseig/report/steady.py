"""The report of a steady motion (DESIGN §8), on the page every motion shares
(:mod:`mbseig.report.page`): the summary, then the configuration's model with its parameters and
units, the steady motion (speed and direction in words, wheel spins, contact forces), the modes
with the verdict and its scope, the mode shapes drawn as the rest report draws them (from
q − q₀(t) = N x of each mode), the pole map and the time-domain check.  Computed by
:mod:`mbseig.studies.steady_report`; this module only formats."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .. import plots
from .provenance import provenance
from .modes import check_table, mode_label
from .page import head_blocks, page_blocks, write_page
from .sections import MAX_DRAWN_MODES, describe, modes_blocks, parameter_blocks, pole_blocks
from .summary import least_mode_text, scope_sentences, verdict_cell
from .text import fmt
from .units import parameter_units

__all__ = ["steady_blocks", "write_steady_report", "motion_text", "direction_text"]


def direction_text(d):
    """A direction as a person reads it: "x", "−y" for a global axis, else its components."""
    d = np.asarray(d, float)
    d = d / max(float(np.linalg.norm(d)), 1e-300)
    k = int(np.argmax(np.abs(d)))
    if abs(abs(d[k]) - 1.0) <= 1e-12:
        return ("" if d[k] > 0 else "−") + "xyz"[k]
    return "(" + ", ".join(f"{x:.4g}" for x in d) + ")"


def motion_text(motion):
    """'Speed 5 m/s along x, yaw rate 0.2 rad/s about the gravity axis'."""
    text = f"Speed {fmt(motion.speed, 6)} m/s along {direction_text(motion.direction)}"
    if motion.yaw_rate:
        text += f", yaw rate {fmt(motion.yaw_rate, 6)} rad/s about the gravity axis"
    return text


def steady_blocks(rep, case, out_dir):
    """The report's blocks (figures written to ``out_dir``)."""
    out_dir = Path(out_dir)
    a, listing = rep.analysis, rep.listing
    tag = rep.config or "base"
    units = parameter_units(case)
    head = head_blocks(rep.name, rep.description, provenance(case), [rep.config],
                       motion="steady")
    summary = [("h2", "Summary"),
               ("table", ["configuration", "verdict", "least-damped mode", "motion"],
                [[tag, verdict_cell(a.verdict), least_mode_text(rep.least_mode),
                  motion_text(a.motion)]])]
    summary += scope_sentences([(tag, a.verdict)])
    body = summary + [("h2", f"Configuration {tag}"),
                      ("p", f"**{tag}**: " + (describe(case, rep.config) if rep.config else
                                              "the case as written, no configuration applied")
                            + "."),
                      ("h3", "Model"), _model_table(a)]
    body += parameter_blocks(case, a.model, units)
    body += _state_blocks(a)
    body += modes_blocks(listing, rep.least)
    body += _shape_blocks(rep, out_dir, tag)
    body += pole_blocks(listing, tag, out_dir / f"{rep.name}_{tag}_poles.png")
    body += _check_blocks(rep)
    return page_blocks(head, body)


def _model_table(a):
    model, st, lin = a.model, a.state, a.linear
    return ("table", ["quantity", "value"], [
        ["coordinates", str(model.n)],
        ["holonomic constraints", str(model.n_constraints)],
        ["velocity constraints (rolling)", str(2 * len(st.spin))],
        ["positions (degrees of freedom)", str(lin.dof)],
        ["independent velocities", str(lin.n_velocities)],
        ["steady-state residual", f"{st.residual:.1e} ({st.iterations} Newton iterations)"],
        ["eigensolver", f"{a.solution.solver} (first-order descriptor pencil E X' = A X, "
                        f"X = [positions; independent velocities])"]])


def _state_blocks(a):
    st = a.state
    spins = ", ".join(f"{fmt(x, 10)} rad/s" for x in st.spin) or "none"
    blocks = [("h3", "Steady motion"),
              ("p", f"{motion_text(a.motion)}. Wheel spins {spins}; the linearization is about "
                    f"this motion, in the frame moving with it.")]
    if st.contacts:
        blocks.append(("table", ["contact", "normal force [N]", "state"],
                       [[c["name"], fmt(c["force"], 10), "active" if c["active"] else "RELEASED"]
                        for c in st.contacts]))
    blocks += [("p", n) for n in a.notes]
    return blocks


def _shape_blocks(rep, out_dir, tag):
    from ..plots.spatial import spatial_modes

    a, listing = rep.analysis, rep.listing
    drawn = list(rep.drawn)[:MAX_DRAWN_MODES.get(3, 6)]
    if not drawn:
        return [("p", "No mode to draw: every mode is rigid-body by construction.")]
    rigid = sum(1 for r in listing.rigid_body if r)
    note = (f"The {rigid} rigid-body mode{'s' if rigid > 1 else ''} by construction (named in "
            f"the table) {'are' if rigid > 1 else 'is'} not drawn. " if rigid else "")
    if len(drawn) < len(listing) - rigid:
        note += (f"The figure draws the lowest {len(drawn)} of the {len(listing) - rigid} counted "
                 "modes.")
    labels = [mode_label(k, listing) for k in drawn]
    fig = spatial_modes(a.model, a.state.q, rep.shapes[:, :len(drawn)], labels,
                        title=f"{tag}: steady motion (black) and mode shapes (±, red/blue)",
                        reference_label="steady motion")
    img = plots.save(fig, out_dir / f"{rep.name}_{tag}_shapes.png")
    blocks = [("p", note.strip())] if note else []
    return blocks + [("img", img, f"{tag}: the system in its steady motion (in the frame moving "
                                  f"with it) and each mode shape q − q₀(t) = N x superposed, "
                                  f"projected back onto the constraints Φ(q) = 0 so bodies stay "
                                  f"rigid")]


def _check_blocks(rep):
    blocks = [("h3", "Time-domain check")]
    chk = rep.check
    if chk is None:
        return blocks + [("p", "Time-domain check not run (report built with --no-check).")]
    tol = chk.tolerances
    blocks.append(("p", f"Each counted mode is excited alone in the nonlinear model (rolling "
                        f"constraints included; DOP853, rtol {tol['ode_rtol']:g}) and its modal "
                        f"coordinate fitted; tolerances: δ {tol['delta_rtol']:g} relative (at "
                        f"least {tol['zero_delta_tol']:g} |s|), ω {tol['omega_rtol']:g} relative; "
                        f"rigid-body modes are not simulated. Result: "
                        + ("all passed." if chk.passed else f"FAILED for {chk.failed}.")))
    blocks.append(check_table(chk, rep.listing))
    return blocks


def write_steady_report(rep, case, out_dir):
    """Write report.md and report.html of a steady motion; returns their paths."""
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    return write_page(steady_blocks(rep, case, out_dir), out_dir,
                      f"Stability report: {rep.name}")

