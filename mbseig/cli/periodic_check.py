"""``mbseig check CASE`` on a periodic case: the nonlinear model perturbed along the Floquet
vector of the largest multiplier, its growth per period against |μ|
(:mod:`mbseig.studies.periodic_check`).  Exit 0 when they agree within the tolerance, 1 when
not."""

from __future__ import annotations

from ..studies.periodic import periodic_analysis
from ..studies.periodic_check import check_floquet
from .common import case_kwargs, number_option, print_json


def run(args, spec) -> int:
    kw = case_kwargs(args)
    amplitude = number_option("--amplitude", args.amplitude, positive=True)
    periods = int(max(2, min(number_option("--periods", args.periods, positive=True), 40)))
    a = periodic_analysis(spec, config=kw["config"], params=kw["params"])
    res = check_floquet(a, amplitude=amplitude, periods=periods,
                        ode_rtol=min(args.ode_rtol, 1e-10))
    if args.json:
        print_json({"case": spec.name, "verdict": a.floquet.verdict,
                    "floquet_check": res.to_dict(), "passed": res.passed})
        return 0 if res.passed else 1
    print(f"case {spec.name}: Floquet multiplier {res.index + 1}, mu = {res.multiplier.real:.8g}"
          f"{res.multiplier.imag:+.8g}j, |mu| = {res.modulus:.10g}")
    print(f"nonlinear simulation along its Floquet vector (amplitude {res.amplitude:.3g}, "
          f"{res.periods} periods): growth per period {res.growth:.10g}, relative error "
          f"{res.relative_error:.2e} (tolerance {res.rtol:g}); off the subspace {res.off_subspace:.1e}")
    print("check: passed" if res.passed else "check: FAILED")
    return 0 if res.passed else 1
