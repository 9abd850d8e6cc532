"""``mbseig frf CASE --input U --output Y``: frequency response, poles, zeros and DC gain."""

from __future__ import annotations

import math

import numpy as np

from ..errors import CaseError, MbseigError
from ..studies.frf import frf, frf_json, write_frf
from ..studies.point import linear_stage
from .common import (
    add_case_arguments,
    case_kwargs,
    case_command,
    number_option,
    print_json,
)


def register(sub):
    p = sub.add_parser("frf", help="frequency response, poles, zeros and DC gain of one input "
                                   "to one output")
    add_case_arguments(p)
    p.add_argument("--input", required=True, metavar="U", help="an input name of [[inputs]]")
    p.add_argument("--output", required=True, metavar="Y", help="an output name of [[outputs]]")
    p.add_argument("--hz", default=None, metavar="F1:F2:N",
                   help="N frequencies from F1 to F2 Hz, log-spaced (linear when F1 = 0); "
                        "default: 500 from a decade below the lowest pole's |s|/2pi to a "
                        "decade above the highest")
    p.add_argument("--out", default=None, metavar="DIR", help="write frf.csv and bode.png to DIR")
    p.set_defaults(run=run)


def parse_hz(text):
    """F1:F2:N → the frequencies (Hz)."""
    parts = text.split(":")
    if len(parts) != 3:
        raise CaseError(f"--hz must be F1:F2:N, got {text!r}", element="command line")
    try:
        lo, hi = float(parts[0]), float(parts[1])
        count = int(parts[2])
    except ValueError:
        raise CaseError(f"--hz must be F1:F2:N with numbers F1, F2 and an integer N, got "
                        f"{text!r}", element="command line") from None
    number_option("--hz F1", lo, nonnegative=True)
    number_option("--hz F2", hi, positive=True)
    if not lo < hi or not 2 <= count <= 100_000:
        raise CaseError(f"--hz needs F1 < F2 and 2 <= N <= 100000, got {text!r}",
                        element="command line")
    return np.linspace(lo, hi, count) if lo == 0 else np.geomspace(lo, hi, count)


@case_command("frf")
def run(args, spec) -> int:
    freq = parse_hz(args.hz) if args.hz is not None else None
    kw = case_kwargs(args)
    model = spec.build(kw["config"], **kw["params"])
    try:
        _, lin = linear_stage(model)
        r = frf(lin, args.input, args.output, freq)
    except MbseigError as exc:
        raise exc.located(file=model.source) from None
    if args.out:
        write_frf(r, args.out)
    if args.json:
        print_json(frf_json(r))
        return 0
    print(f"case {model.name}: {args.input} -> {args.output} ({lin.dof} DOF)")
    dc = "none (a rigid-body mode)" if r.dc_gain is None else f"{r.dc_gain:.6g}"
    print(f"DC gain: {dc}")
    for what, vals in (("poles", r.poles), ("zeros", r.zeros)):
        print(f"{what} ({len(vals)}):")
        for z in vals:
            wn = abs(z)
            print(f"  {z.real:>14.6g} {z.imag:+14.6g}j   |s|/2pi = {wn / (2 * math.pi):.6g} Hz")
    for item in r.singular:
        f = item["freq_hz"]
        print(f"pole on the grid at {f:.6g} Hz: the response is unbounded (null in the JSON)"
              if item["status"] == "pole" else
              f"pole on the grid at {f:.6g} Hz that the input does not drive or the output "
              f"does not see: the response there is the transfer function's limit")
    if args.out:
        print(f"wrote {args.out}/frf.csv and {args.out}/bode.png")
    return 0
