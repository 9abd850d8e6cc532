"""The spatial rows of the EXUDYN peer comparison (mbseig.bench.peer.bench_peer_spatial).

References:
- closed forms independent of both codes: the damped spherical pendulum's swings
  (J + m l²)s² + c s + m g l = 0 per axis and spin J_z s² + c_z s = 0; the spatial double
  pendulum's linearized compound-pendulum frequencies (cases/spatial_double_pendulum.toml's
  source).  mbseig must meet them to 1e-12 (pendulum) and 1e-7 (double pendulum: its four s = 0
  of the free spins are double roots, computed to √ε relative, ≈ 3e-8 measured; the swings to
  1e-12, checked separately).
- the two sides' eigenvalue sets on the pendulum, where EXUDYN (with its load Jacobian) is exact:
  they agree to 1e-12 of max(|s|, smallest nonzero |s|).
- EXUDYN's stock ``ComputeODE2Eigenvalues``: the step-by-step replica with the load Jacobian
  off must give its eigenvalues to 1e-12 (the replica is EXUDYN's own computation), and with it
  on must differ (gravity stiffness: the swings move from s = 0 or −c/I to |s| ≈ 3.5).
Skipped without exudyn.
"""

import numpy as np
import pytest

pytest.importorskip("exudyn")

from mbseig.bench import peer


@pytest.fixture(scope="module")
def rows():
    out, note = peer.bench_peer_spatial(1, lambda *a: None)
    assert note == ""
    return {r["model"]: r for r in out}


def _arr(pairs):
    return np.array([complex(a, b) for a, b in pairs])


def test_pendulum_both_sides_agree_with_the_closed_form(rows):
    r = rows["spherical pendulum, damped pivot"]
    assert r["mbseig_solver"] == "companion"  # cx ≠ cy ≠ cz: not proportional, general path
    assert r["mbseig_error"] <= 1e-12 and r["mbseig_error_nonzero"] <= 1e-12
    assert r["exudyn_error"] <= 1e-12 and r["exudyn_error_nonzero"] <= 1e-12
    assert r["set_distance"] <= 1e-12
    assert r["mbseig_eta"] <= 1e-14 and r["exudyn_eta"] <= 1e-14
    assert r["exudyn_count"] == 6 and len(r["reference"]) == 6


def test_double_pendulum_mbseig_meets_the_closed_form(rows):
    r = rows["spatial double pendulum"]
    assert r["mbseig_error"] <= 1e-7
    s, ref = _arr(r["mbseig_eigenvalues"]), _arr(r["reference"])
    swings = ref[np.abs(ref) > 0]
    for z in swings:  # the swings themselves to 1e-12
        assert np.min(np.abs(s - z)) <= 1e-12 * abs(z)
    assert r["mbseig_error_nonzero"] <= 1e-12
    assert r["mbseig_eta"] <= 1e-14


def test_replica_is_exudyns_stock_call_with_the_load_jacobian_off():
    for key in peer.SPATIAL_MODELS:
        p = peer.SPATIAL_MODELS[key][1]
        _sc, mbs = peer._exudyn_spatial(key, p)  # the container owns mbs: keep it alive
        stock = peer._exudyn_stock(mbs)
        replica = peer._exudyn_eigenvalues(mbs, loads_jacobian=False)
        assert stock.size == replica.size
        assert peer._scaled_set_distance(stock, replica, 1.0) <= 1e-12  # |s| ≤ 10 here
        with_loads = peer._exudyn_eigenvalues(mbs)
        assert peer._scaled_set_distance(stock, with_loads, 1.0) > 0.1  # the flag matters


def test_peer_lines_print_the_spatial_table(rows):
    lines = peer.peer_lines(list(rows.values()), "")
    text = "\n".join(lines)
    assert "spatial constrained models" in text
    assert "| spherical pendulum, damped pivot |" in text and "| spatial double pendulum |" in text
    assert "Chain rows not run." in text
