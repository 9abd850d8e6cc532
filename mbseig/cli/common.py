"""Options shared by the subcommands."""

from __future__ import annotations

import functools
import json
import os
import sys

from ..casefile import parse_param_overrides
from ..casefile.fields import RANGE_RULE, in_range
from ..errors import CaseError, MbseigError
from ..numerics import jsonable

__all__ = ["add_case_arguments", "case_kwargs", "print_json", "print_reactions", "number_option",
           "output_notes", "equilibrium_notes", "case_command",
           "analyzed", "parameter_units_of", "add_progress_options", "show_progress",
           "add_study_options", "KeptStudy", "resume_dir"]

#: the --jobs help: the rule of mbseig.studies.runners (its module docstring)
JOBS_HELP = ("local worker processes (default: decided per stage: its first 2 tasks run "
             "in-process and are timed, and the rest goes to a pool of one process per free "
             "CPU (those the load average leaves) only when that is predicted at least 25%% "
             "faster, counting the pool's start-up and the transfer of each task; else "
             "in-process); 1 runs in-process")


def add_case_arguments(parser):
    parser.add_argument("case", metavar="CASE", help="case file (TOML)")
    parser.add_argument("--param", action="append", default=[], metavar="NAME=VALUE",
                        help="override a case parameter (repeatable); VALUE may be an expression")
    parser.add_argument("--config", default=None, metavar="NAME",
                        help="a named configuration of the case's [configurations] table")
    parser.add_argument("--json", action="store_true", help="print one JSON object")


def add_progress_options(parser, what="the progress bar"):
    """``--progress`` / ``--no-progress``: ``what`` on stderr always / never (default: only when
    stderr is a terminal; :func:`show_progress`)."""
    prog = parser.add_mutually_exclusive_group()
    prog.add_argument("--progress", dest="progress", action="store_true", default=None,
                      help=f"always show {what} on stderr")
    prog.add_argument("--no-progress", dest="progress", action="store_false",
                      help="never show it (default: only when stderr is a terminal)")


def add_study_options(parser):
    """``--jobs N`` and ``--resume DIR`` of a study over a grid (the sweeps)."""
    parser.add_argument("--jobs", type=_jobs, default=None, metavar="N", help=JOBS_HELP)
    parser.add_argument("--resume", default=None, metavar="DIR",
                        help="keep every completed line, point and boundary in DIR as it "
                             "completes; rerun with the same DIR to compute only the missing "
                             "ones (the outputs equal those of an uninterrupted sweep).  "
                             "Without it, Ctrl-C keeps the finished points in OUT-resume "
                             "next to --out")


def _jobs(text):
    import argparse

    try:
        n = int(text)
    except ValueError:
        n = 0
    if n < 1:
        raise argparse.ArgumentTypeError(f"must be a positive integer, got {text!r}")
    return n


def resume_dir(out_dir) -> str:
    """Where an interrupted study without --resume keeps its finished points: OUT-resume,
    next to its output directory OUT."""
    from pathlib import Path

    out = Path(out_dir)
    return str(out.with_name(out.name + "-resume"))


class KeptStudy:
    """What an interrupted study keeps, and the one line that says so.

    ``checkpoint`` (give it to the study as ``resume=``): with ``--resume DIR`` every task is
    written to DIR as it completes; without, the tasks are held in memory and written to
    ``default_dir`` (next to ``--out``) only when the study is interrupted.  :meth:`say`
    (on the first Ctrl-C, or from a second one, ``mbseig.cli.ON_SECOND_INTERRUPT``) writes
    what is held and prints, once::

        mbseig: interrupted after N of M points; rerun with --resume DIR to finish
    """

    def __init__(self, resume, default_dir, total, *, close=None):
        from ..studies.resume import Checkpoint
        from . import ON_SECOND_INTERRUPT

        self.checkpoint = Checkpoint(resume if resume is not None else default_dir,
                                     deferred=resume is None)
        self.checkpoint.points[:] = [0, int(total)]
        self.close = close  # run before the line (a progress bar ends its own line)
        self.said = False
        self._hooks = ON_SECOND_INTERRUPT
        self._hook = functools.partial(self.say, raw=True)  # (in a signal handler)
        self._hooks.append(self._hook)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        if self._hook in self._hooks:
            self._hooks.remove(self._hook)
        return False

    def say(self, exc=None, *, raw=False) -> int:
        """Keep the finished tasks and print the line (once); the exit code 130.  ``raw``:
        written straight to file descriptor 2 (from a signal handler, which may have cut a
        write to sys.stderr short)."""
        from . import held

        if self.said:
            return 130
        self.said = True
        with held():
            if self.close is not None:
                try:
                    self.close()
                except Exception:  # (a bar that cannot draw: the line matters more)
                    pass
            text = self._line(exc)
            if raw:
                try:
                    sys.stderr.flush()
                except Exception:  # (a write cut short by the signal)
                    pass
                os.write(2, (text + "\n").encode())
            else:
                print(text, file=sys.stderr)
                sys.stderr.flush()
        return 130

    def _line(self, exc) -> str:
        import shlex

        done, total = self.checkpoint.points
        if done == 0 and self.checkpoint.identity is None:  # stopped before the study began
            return f"mbseig: interrupted before the first of {total} points"
        try:
            where = self.checkpoint.flush()
        except MbseigError as err:
            return (f"mbseig: interrupted after {done} of {total} points; they could not be "
                    f"kept: {' '.join(err.one_line().splitlines())}")
        stage = getattr(exc, "stage", "") or ""
        more = f" ({stage} done)" if stage and done >= total else ""
        return (f"mbseig: interrupted after {done} of {total} points; rerun with --resume "
                f"{shlex.quote(str(where))} to finish{more}")


def show_progress(args) -> bool:
    """Whether to draw progress: as asked, else when stderr is a terminal."""
    return args.progress if args.progress is not None else sys.stderr.isatty()


def case_kwargs(args) -> dict:
    return {"config": args.config, "params": parse_param_overrides(args.param)}


def print_json(obj) -> int:
    """Print ``obj`` as one JSON object; returns the command's exit code 0."""
    json.dump(jsonable(obj), sys.stdout, indent=1, allow_nan=False)
    sys.stdout.write("\n")
    return 0


def parameter_units_of(spec) -> dict:
    """``{parameter: unit}`` of a read case for the figures' axes (mbseig.report.units), only
    the parameters with a unit; {} when the case's text cannot be read for them."""
    from ..report.units import parameter_units

    try:
        return {k: v for k, v in parameter_units(spec).items() if v}
    except (OSError, AttributeError, TypeError):
        return {}


def analyzed(args, spec, analyze):
    """``analyze(spec, config=..., params=...)`` with the command line's configuration and
    parameter overrides (the moving-case analyses take the case as read once)."""
    kw = case_kwargs(args)
    return analyze(spec, config=kw["config"], params=kw["params"])


def print_reactions(rows):
    """The reaction table of :func:`mbseig.statics.reactions.reaction_forces`: per joint the
    force and moment on the body it names, about the joint point, in global axes and in that
    body's axes; per other constraint what it carries and the force on each point.  A value
    within its error bound is printed as 0; the bodies' normalization conditions (internal to
    their coordinates) are summarized, not listed."""
    if not rows:
        return
    def fmt(v):
        return "(" + ", ".join(f"{x:.6g}" for x in v) + ")"

    def _carried_text(r):  # what the multipliers carry as the element states it, its bound
        c, err = r["reaction"], r["reaction_error"]
        value = c["value"] if isinstance(c["value"], list) else [c["value"]]
        err = err if isinstance(err, list) else [err]
        return (f"{c['label']} {', '.join(f'{v:.6g}' for v in value)} {c['unit']}".rstrip()
                + f" (± {max(err, default=0.0):.2g})")
    bound = max((r.get("lambda_bound", 0.0) for r in rows), default=0.0)
    print("reactions at equilibrium: per joint the force F and moment M on the body named, about "
          "the joint point; per other constraint what it carries and the force on each point")
    print("  (a value within its error bound is printed as 0; the bound of a value a·λ is "
          f"‖a‖ δλ + γ |a|·|λ| + the position error's share, δλ = (‖g − Φ_qᵀλ‖ + rounding) / "
          f"σ_min(Φ_q) ≤ {bound:.2g})")
    internal = [r for r in rows if r.get("kind") == "internal"]
    for r in rows:
        kind = r.get("kind")
        if kind == "internal":
            continue
        if kind in ("joint", "shared point", "on body"):
            b, err = r["on"], r["error"]
            where = {"shared point": f" (point {r.get('point')}, shared by "
                                     f"{', '.join(r.get('shared_by', ()))})",
                     "on body": f" ({_carried_text(r)}; moment about {r['on']}'s origin)"
                     }.get(kind, "")
            print(f"  {r['element']}{where} on {b} at {fmt(r['at'])} m:")
            axes = ("global x, y, z", f"{b} u, v, w")
            w = max(map(len, axes)) + 1
            print(f"      {axes[0] + ':':<{w}} F = {fmt(r['force'])} N, M = {fmt(r['moment'])} N m")
            print(f"      {axes[1] + ':':<{w}} F = {fmt(r['force_body'])} N, "
                  f"M = {fmt(r['moment_body'])} N m")
            print(f"      error bound: F {max(err['force_body']):.2g} N, "
                  f"M {max(err['moment_body']):.2g} N m")
            continue
        carried = _carried_text(r)
        on_body = r.get("forces_body_on", {})
        parts = []
        for p, f in r["forces"].items():
            text = f"{p} {fmt(f)} N"
            if p in on_body:
                text += f" = {fmt(r['forces_body'][p])} in {on_body[p]}'s axes"
            parts.append(text)
        print(f"  {r['element']}: {carried}; force on point {'; '.join(parts)}")
    if any(r.get("kind") == "body" or r.get("forces_body_on") for r in rows):
        print("  (a planar body's axes: x from its first to its second point, y normal, "
              "counter-clockwise)")
    if any(r.get("kind") in ("joint", "shared point", "on body") for r in rows):
        print("  (a spatial body's axes u, v, w are parallel to global x, y, z at the reference)")
    if internal:
        owners = list(dict.fromkeys(str(r.get("on") or r["element"].rsplit(" (", 1)[0])
                                    for r in internal))
        owners = ", ".join(owners[:4] + ([f"{len(owners) - 4} more"] if len(owners) > 4 else []))
        print(f"  not listed: {len(internal)} normalization condition(s) of the bodies' unit "
              f"vectors u, v, w ({owners}): internal to the body coordinates, no joint force")


def number_option(name, value, *, positive=False, nonnegative=False, minimum=None):
    """A numeric command-line option checked like a case number (finite, 0 or of magnitude
    1e-100 to 1e100), and positive, non-negative or at least ``minimum`` where the option says
    so (None passes through)."""
    if value is None:
        return None
    rule = ("a positive number" if positive else "a non-negative number" if nonnegative
            else f"a number >= {minimum:g}" if minimum is not None else "a number")
    ok = in_range(value) and (not positive or value > 0) and (
        not nonnegative or value >= 0) and (minimum is None or value >= minimum)
    if not ok:
        raise CaseError(f"{name} must be {rule} ({RANGE_RULE}), got {value!r}",
                        element="command line")
    return value


def output_notes(model, eq):
    """What the reported warnings said (mbseig.errors.ReportedWarning), for the output: the
    beam-theory guidance of every beam and the equilibrium's notes."""
    bodies = (model.flexible or {}).get("bodies") or {}
    return ([f"beam {nm}: {w}" for nm, r in bodies.items() for w in r.get("warnings", ())]
            + [f"equilibrium: {n}" for n in equilibrium_notes(eq)])


def equilibrium_notes(eq):
    """The equilibrium's notes (static stability, self-stress), as strings."""
    return [str(n) for n in (getattr(eq, "notes", None) or ())]


def case_command(command, rest=None, **moving):
    """``mbseig COMMAND`` on a case whatever reference motion it declares: the case is read once,
    its reference is the one its ``[motion]`` table declares
    (:func:`mbseig.studies.reference.reference_kind`: rest, steady or periodic) and ``run(args,
    spec)`` of that reference runs (``rest``, and ``steady=`` / ``periodic=`` where the command
    analyses those); a reference the command does not analyse is refused in one line, never run
    as if the case were at rest.  Used as ``@case_command("frf")`` on the rest handler, or
    called with every handler."""
    def bind(run_rest):
        handlers = {"rest": run_rest, **moving}

        @functools.wraps(run_rest)
        def run(args) -> int:
            from ..studies.point import as_spec
            from ..studies.reference import reference_kind

            spec = as_spec(args.case)
            kind = reference_kind(spec)
            handler = handlers.get(kind)
            if handler is None:
                raise CaseError(f"mbseig {command} does not analyse {kind} motions ([motion] "
                                f"with {'period' if kind == 'periodic' else 'speed'})",
                                element="motion", file=spec.source)
            return handler(args, spec)
        return run
    return bind if rest is None else bind(rest)
