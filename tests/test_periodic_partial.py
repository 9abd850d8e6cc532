"""The partial (Arnoldi) Floquet method of ``mbseig modes --n-modes K`` on a periodic case,
against the full monodromy of the same case (independent method: every multiplier from the
dense monodromy matrix), on cases/column_pulsating_load.toml (3 DOF, 6 multipliers)."""

from conftest import CASES

from mbseig.casefile import read_case
from mbseig.cli import main

CASE = CASES / "column_pulsating_load.toml"


def test_partial_method_matches_full_monodromy(capsys):
    """The partial (Arnoldi) method that ``modes --n-modes K`` runs gives the dominant
    multiplier of the full monodromy within the two methods' bounds and the same verdict
    (tolerances 1e-8/1e-10 here to keep the suite fast); the modes JSON of ``--n-modes`` has the
    §8 keys; K beyond what ARPACK can give is refused in one line."""
    from mbseig.studies.periodic_listing import partial_json
    from mbseig.studies.periodic import periodic_analysis
    from mbseig.studies.periodic_partial import periodic_partial

    spec = read_case(CASE)
    p = periodic_partial(spec, k=1, rtols=(1e-8, 1e-10), tol=1e-9)
    out = partial_json(p)
    part, full = out["floquet"], periodic_analysis(spec).floquet.to_dict()
    assert {"period", "multipliers", "exponents", "error_bound", "verdict"} <= set(part)
    assert part["verdict"] == full["verdict"] == out["verdict"] == "unstable"
    assert part["partial"]["of"] == 6 and part["partial"]["products"] > 0
    mu_p, mu_f = complex(*part["multipliers"][0]), complex(*full["multipliers"][0])
    assert abs(mu_p - mu_f) <= part["error_bounds"][0] + full["error_bounds"][0]
    assert part["error_bounds"][0] < 1e-6
    assert out["modes"][0]["stability"] == "unstable"
    assert main(["modes", str(CASE), "--n-modes", "5"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "--n-modes must be between 1 and" in err
