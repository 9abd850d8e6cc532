"""The K largest Floquet multipliers of ``mbseig modes --n-modes K`` on a periodic case: the
partial (Arnoldi) method (``--floquet partial``) against the full monodromy of the same case
(independent method: every multiplier from the dense monodromy matrix), on
cases/pendulum_chain_shaken.toml at n = 3 (3 DOF, 6 multipliers), and the default answer from
the full monodromy on cases/column_pulsating_load.toml (3 DOF, 6 multipliers)."""

from conftest import CASES

from mbseig.casefile import read_case
from mbseig.cli import main

CASE = CASES / "column_pulsating_load.toml"


def test_partial_method_matches_full_monodromy(capsys):
    """The partial (Arnoldi) method that ``modes --n-modes K --floquet partial`` runs gives the
    dominant multiplier of the full monodromy within the two methods' bounds and the same
    verdict (tolerance 1e-10 here to keep the suite fast); the modes JSON of
    ``--n-modes`` has the §8 keys; K beyond what ARPACK can give is refused in one line."""
    from mbseig.studies.periodic_listing import partial_json
    from mbseig.studies.periodic import periodic_analysis
    from mbseig.studies.periodic_partial import periodic_partial

    spec = read_case(CASES / "pendulum_chain_shaken.toml")
    p = periodic_partial(spec, k=1, params={"n": 3}, rtol=1e-10, tol=1e-9)
    out = partial_json(p)
    part, full = out["floquet"], periodic_analysis(spec, params={"n": 3}).floquet.to_dict()
    assert {"period", "multipliers", "exponents", "error_bound", "verdict"} <= set(part)
    assert part["verdict"] == full["verdict"] == out["verdict"] == "unstable"
    assert part["partial"]["of"] == 6 and part["partial"]["products"] > 0
    mu_p, mu_f = complex(*part["multipliers"][0]), complex(*full["multipliers"][0])
    assert abs(mu_p - mu_f) <= part["error_bounds"][0] + full["error_bounds"][0]
    assert part["error_bounds"][0] < 1e-6
    assert out["modes"][0]["stability"] == "unstable"
    assert main(["modes", str(CASE), "--n-modes", "5", "--floquet", "partial"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "--n-modes must be between 1 and" in err


def test_n_modes_takes_the_largest_from_the_full_monodromy(capsys):
    """``--n-modes K`` (``--floquet auto``) answers from the full monodromy (docs/periodic.md,
    "Floquet at scale"): its listing is the full analysis's K multipliers of largest modulus
    (the same computation: equal to the last bit), a complex one completed by its conjugate,
    with the full analysis's verdict and bounds, and ``selected`` saying how many of how many
    and why; K up to every multiplier is accepted (no ARPACK limit there)."""
    import json

    from mbseig.studies.periodic import periodic_analysis

    full = periodic_analysis(read_case(CASE)).floquet.to_dict()
    for k, listed in ((1, 1), (2, 3), (6, 6)):  # 2: the pair at |mu| = 1 comes whole
        assert main(["modes", str(CASE), "--n-modes", str(k), "--json"]) == 0
        out = json.loads(capsys.readouterr().out)
        fl = out["floquet"]
        assert fl["selected"]["count"] == listed and fl["selected"]["of"] == 6
        assert fl["selected"]["method"].startswith("full monodromy")
        assert fl["multipliers"] == full["multipliers"][:listed]
        assert fl["error_bounds"] == full["error_bounds"][:listed]
        assert out["verdict"] == full["verdict"] == "unstable"


def test_floquet_option_refused_where_it_means_nothing(capsys):
    """``--floquet`` without ``--n-modes``, or on a case at rest: one line naming the file and
    the command line, exit 2 (never ignored)."""
    for case, argv in ((CASE, ["--floquet", "partial"]),
                       (CASES / "pendulum.toml", ["--n-modes", "1", "--floquet", "full"])):
        assert main(["modes", str(case), *argv]) == 2
        err = capsys.readouterr().err.strip()
        assert len(err.splitlines()) == 1 and err.startswith(f"mbseig: {case}: command line:")
        assert "--floquet" in err
