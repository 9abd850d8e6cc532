"""``mbseig bench``: time and accuracy side by side (see :mod:`mbseig.bench`)."""

from __future__ import annotations


def register(sub):
    p = sub.add_parser("bench", help="measure speed against accuracy; write reports/benchmarks.md")
    p.add_argument("--quick", action="store_true", help="small sizes only (about a minute)")
    p.add_argument("--out", default=None, metavar="DIR",
                   help="output directory (default: reports/)")
    p.add_argument("--repeats", type=int, default=None,
                   help="runs per point (median); default 3, quick 1")
    p.add_argument("--threads", type=int, default=1,
                   help="BLAS threads during the measurements (0: library default)")
    p.add_argument("--sections", nargs="+", default=None,
                   choices=["dense", "structured", "partial", "large", "startup", "peer",
                            "sweeps", "jacobians", "constraint", "timedomain", "failures", "nlevp",
                            "rotor", "beams", "slepc", "spatial", "batch",
                            "uncertainty", "lean"],
                   help="run only these sections")
    p.set_defaults(run=run)


def run(args) -> int:
    from ..bench import run_bench

    res = run_bench(quick=args.quick, out_dir=args.out, repeats=args.repeats, threads=args.threads,
                    sections=args.sections, log=lambda s: print(s, flush=True))
    print(f"wrote benchmarks.md, benchmarks.json and speed_accuracy.png ({res['elapsed']:.0f} s)")
    return 0
