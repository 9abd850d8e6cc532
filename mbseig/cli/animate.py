"""``mbseig animate CASE --mode K --out mode.gif``: one period of a mode as a looping GIF.

The mode is numbered as in ``mbseig modes`` and the report's mode table; the drawing is the one
of the report's still pictures (:mod:`mbseig.plots.animation`): bodies rigid, moved along the
mode and projected back onto the constraints.
"""

from __future__ import annotations

from ..errors import CaseError
from .common import case_kwargs, case_command, number_option

HELP = "write one period of a mode shape as a looping GIF"


def register(sub):
    p = sub.add_parser("animate", help=HELP)
    p.add_argument("case", metavar="CASE", help="case file (TOML)")
    p.add_argument("--mode", type=int, required=True, metavar="K",
                   help="mode number, as in the mode table of `mbseig modes` (1 = first)")
    p.add_argument("--param", action="append", default=[], metavar="NAME=VALUE",
                   help="override a case parameter (repeatable); VALUE may be an expression")
    p.add_argument("--config", default=None, metavar="NAME",
                   help="a named configuration of the case's [configurations] table")
    p.add_argument("--out", default=None, metavar="FILE.gif",
                   help="output file (default: CASE_modeK.gif in the current directory)")
    p.add_argument("--frames", type=int, default=16, metavar="N",
                   help="frames in one period (default 16)")
    p.add_argument("--fps", type=float, default=12.0, metavar="F",
                   help="frames per second (default 12)")
    p.add_argument("--amplitude", type=float, default=0.12, metavar="A",
                   help="largest displacement as a fraction of the model's size (default 0.12)")
    p.set_defaults(run=run)


@case_command("animate")
def run(args, spec) -> int:
    from pathlib import Path

    from ..model.linear_case import LinearCase
    from ..studies import analyze

    if args.frames < 2 or args.frames > 500:
        raise CaseError(f"--frames must be an integer from 2 to 500, got {args.frames}",
                        element="command line")
    number_option("--fps", args.fps, positive=True)
    number_option("--amplitude", args.amplitude, positive=True)
    out = Path(args.out) if args.out else None
    if out is not None and out.suffix.lower() != ".gif":
        raise CaseError(f"--out must name a .gif file, got {args.out!r}", element="command line")
    kw = case_kwargs(args)
    a = analyze(spec, config=kw["config"], params=kw["params"])
    if isinstance(a.model, LinearCase):
        raise CaseError("a linear case (matrices only) has no mechanism to animate",
                        file=str(args.case), element="animate")
    md = a.modes
    n = len(md)
    if n == 0:
        raise CaseError("the case has no modes to animate (no degree of freedom)",
                        file=str(args.case), element="--mode")
    if not 1 <= args.mode <= n:
        raise CaseError(f"mode {args.mode} does not exist: the case has {n} mode"
                        f"{'s' if n > 1 else ''} (1 to {n}, as listed by mbseig modes)",
                        file=str(args.case), element="--mode")
    from ..plots.animation import oscillates, write_mode_gif
    from ..report.modes import mode_label
    from ..studies.report_studies import listing_of_modes

    k = args.mode - 1
    model = a.eq.model if a.eq.model is not None else a.model
    out = out or Path(f"{spec.name}_mode{args.mode}.gif")
    write_mode_gif(model, a.eq.q, md.shapes[:, k], out, label=mode_label(k, listing_of_modes(md)),
                   oscillatory=oscillates(md.kind[k], md.eigenvalues[k]), frames=args.frames,
                   fps=args.fps, amplitude=args.amplitude)
    print(f"wrote {out} ({args.frames} frames, one period, looping)")
    return 0
