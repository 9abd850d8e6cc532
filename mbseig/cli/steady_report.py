"""``mbseig report CASE`` on a steady motion (DESIGN §8): report.md and report.html with the
motion, the steady state (residual, spins, each wheel's normal force and state), the modes with
their measures and shapes, and the time-domain check (unless ``--no-check``).  The numbers come
from :mod:`mbseig.studies.steady_modes` and :mod:`mbseig.studies.steady_check`; this module
only formats them."""

from __future__ import annotations

import html
from pathlib import Path

from ..errors import CaseError

__all__ = ["run"]


def _table(head, rows):
    md = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    md += ["| " + " | ".join(str(c) for c in r) + " |" for r in rows]
    page = ("<table><tr>" + "".join(f"<th>{html.escape(h)}</th>" for h in head) + "</tr>"
            + "".join("<tr>" + "".join(f"<td>{html.escape(str(c))}</td>" for c in r) + "</tr>"
                      for r in rows) + "</table>")
    return "\n".join(md), page


def run(args, spec) -> int:
    from ..studies.steady_check import check_steady
    from ..studies.steady_modes import analyze_steady

    configs = getattr(args, "config", None) or [None]
    if len(configs) > 1 or getattr(args, "all_configs", False):
        raise CaseError("a steady-motion report covers one configuration (one --config)",
                        element="command line")
    a = analyze_steady(spec, config=configs[0])
    out = Path(args.out) if args.out else Path("reports") / spec.name
    out.mkdir(parents=True, exist_ok=True)
    m, st = a.motion, a.state
    blocks = [("h1", f"{a.model.name}: steady motion"),
              ("p", str(spec.data.get("title", ""))),
              ("p", f"Speed {m.speed:g} along {list(m.direction)}"
                    + (f", yaw rate {m.yaw_rate:g} about the gravity axis" if m.yaw_rate else "")
                    + f". {a.model.n} coordinates, {a.model.n_constraints} holonomic and "
                      f"{2 * len(st.spin)} velocity constraints; the linearization is the "
                      f"descriptor system E X' = A X with {a.linear.dof} positions and "
                      f"{a.linear.n_velocities} independent velocities."),
              ("h2", "Steady state"),
              ("p", (f"Residual {st.residual:.3g} after {st.iterations} Newton iterations; "
                     f"wheel spins {', '.join(f'{x:.10g}' for x in st.spin) or 'none'} rad/s.")),
              ("table", _table(["contact", "normal force [N]", "state"],
                               [[c["name"], f"{c['force']:.10g}",
                                 "active" if c["active"] else "RELEASED"]
                                for c in st.contacts]))]
    blocks += [("p", n) for n in a.notes]
    blocks += [("h2", f"Modes (verdict: {a.verdict})"),
               ("table", _table(["#", "Re s", "Im s", "zeta", "kind", "stability", "eta", "kappa",
                                 "dominant coordinates"],
                                [[r["index"], f"{r['eigenvalue'][0]:+.10g}",
                                  f"{r['eigenvalue'][1]:.10g}", f"{r['zeta']:+.4f}", r["kind"],
                                  r["stability"], f"{r['backward_error']:.1e}",
                                  f"{r['condition']:.1e}",
                                  ", ".join(f"{n} {v:.2f}" for n, v in r.get("dominant", []))]
                                 for r in a.modes]))]
    if not getattr(args, "no_check", False):
        chk = check_steady(spec, config=configs[0], periods=5.0)
        rows = [[c.index, c.kind, f"{c.predicted_delta:+.6g}", f"{c.predicted_omega:.6g}",
                 f"{c.measured_delta:+.6g}", f"{c.measured_omega:.6g}",
                 "passed" if c.passed else "FAILED"] for c in chk.modes if not c.skipped]
        blocks += [("h2", "Time-domain check (nonlinear model, rolling constraints included)"),
                   ("table", _table(["#", "kind", "delta", "omega", "measured delta",
                                     "measured omega", "result"], rows)),
                   ("p", "check: " + ("passed" if chk.passed else "FAILED") + "; rigid-body "
                         "modes are not simulated.")]
    md, page = [], []
    for kind, content in blocks:
        if kind == "table":
            md.append(content[0])
            page.append(content[1])
        elif kind == "p":
            md.append(content)
            page.append(f"<p>{html.escape(content)}</p>")
        else:
            md.append(("# " if kind == "h1" else "## ") + content)
            page.append(f"<{kind}>{html.escape(content)}</{kind}>")
    (out / "report.md").write_text("\n\n".join(md) + "\n")
    (out / "report.html").write_text("<!DOCTYPE html><html><head><meta charset='utf-8'><title>"
                                     + html.escape(a.model.name) + "</title></head><body>"
                                     + "\n".join(page) + "</body></html>\n")
    print(f"wrote {out / 'report.md'} and {out / 'report.html'}")
    return 0
