"""Rigid-body directions of many models at once (mbseig.model.symmetry_batch) against the
one-model search (mbseig.model.symmetry.rigid_directions).

Reference: rigid_directions on each model alone, an independent path (its own element terms from
each element's methods, its own SVDs, one model at a time).  Both apply the same tests at the
same TOL, so they must keep the same directions with the same names; the spans agree to the
rounding of the null-space computations: a basis vector of one lies in the span of the other to
1e-8 (the tests' TOL of 1e-11 on scaled residuals, times the conditioning of the generators,
O(10²) for these models, is far below it).  A model left to the one-model search (None) is
allowed only where its number of directions differs from the batch's majority.
"""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest

from mbseig.casefile import read_case
from mbseig.linear import linearize
from mbseig.model.symmetry import rigid_directions
from mbseig.model.symmetry_batch import rigid_directions_batch
from mbseig.statics import equilibrium

CASES = Path(__file__).resolve().parents[1] / "cases"

LINES = [("spatial_double_pendulum", None, "m1", np.linspace(0.5, 3.0, 12)),
         ("spatial_double_pendulum", None, "l1", np.linspace(0.4, 0.9, 12)),
         ("heavy_top", None, "m", np.linspace(0.5, 2.0, 8)),
         ("chain_free_free", None, "k", np.linspace(50.0, 200.0, 8)),
         ("rigid_rotor", None, "kx", np.linspace(1e4, 5e4, 8)),
         ("spherical_pendulum", None, "l", np.linspace(0.5, 1.2, 8)),
         ("hand_device", "C4", "f", np.linspace(0.0, 2.5, 8))]


@pytest.mark.parametrize("case,config,name,grid", LINES,
                         ids=[f"{c}-{n}" for c, _, n, _ in LINES])
def test_batch_equals_the_one_model_search(case, config, name, grid):
    spec = read_case(CASES / f"{case}.toml")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        models = [spec.build(config, **{name: float(v)}) for v in grid]
        eqs = [equilibrium(m) for m in models]
        lins = [linearize(m, e, signals=False) for m, e in zip(models, eqs, strict=True)]
    got = rigid_directions_batch(models, np.stack([e.q for e in eqs]),
                                 np.stack([e.lam for e in eqs]),
                                 np.stack([np.asarray(x.Q) for x in lins]),
                                 np.stack([np.asarray(x.N) for x in lins]))
    ref = [rigid_directions(m, e.q, e.lam, x.Q, x.N)
           for m, e, x in zip(models, eqs, lins, strict=True)]
    counts = [len(r) for r in ref]
    major = max(set(counts), key=counts.count)
    for g, r in zip(got, ref, strict=True):
        if g is None:
            assert len(r) != major
            continue
        assert g.names == r.names
        if len(r):
            inside = g.vectors @ (g.vectors.T @ r.vectors)
            assert np.abs(inside - r.vectors).max() <= 1e-8
