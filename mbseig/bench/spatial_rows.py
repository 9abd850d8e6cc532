"""Rows of the ``mbseig bench`` report for a large spatial model: a chain of 10⁴ spatial rigid
bodies joined by 6×6 bushings (a rigid-segment model of a clamped-clamped 2 m shaft), read and
assembled (``load_case``: the case's ``repeat`` tables expanded, N bodies and N + 1 bushings
built) and its first evaluation of Φ, Φ_q, g and K, C, against a floor (tomllib alone on the same
text, and M and Φ_q formed as CSR from their own triplets: what any reader of this case must at
least do).  Goal (issue "Fast at every size"): read + assembled ≤ 5 s.
``benchmarks/spatial_chain.py`` runs the same model through the whole pipeline.

Row keys: ``section`` "spatial", ``method``, ``n`` (bodies), ``coordinates``, ``time`` (median
of read + assemble + first evaluation), ``stages`` (medians), ``floor``, ``repeats``, ``load``.
"""

from __future__ import annotations

import os
import statistics
import tempfile
import time
import tomllib
from pathlib import Path

__all__ = ["CASE", "bench_spatial", "build_chain"]

CASE = """
schema_version = 1
title = "chain of {n} spatial rigid bodies on bushings"
dimension = 3

[parameters]
n = {n}
Lt = 2.0            # length of the chain [m]: a 2 m shaft cut into n rigid segments
h = "Lt / n"
rhoA = 8.0          # mass per length [kg/m]
m = "rhoA * h"
Jp = "m * 1e-3"     # polar and transverse inertia of a segment (radius ~ 0.045 m)
Jt = "m * (5e-4 + h**2 / 12)"
EA = 2e8            # axial and shear stiffness [N]
EI = 2e4            # bending stiffness [N m^2] (1.5 EI about z: no repeated pairs)
GJ = 1.5e4          # torsional stiffness [N m^2]
k = "EA / h"
kr = "EI / h"
kt = "GJ / h"

[[bodies]]
repeat = {{ i = [1, "n"] }}
name = "b{{i}}"
mass = "m"
com = ["(i - 0.5) * h", 0.0, 0.0]
inertia = ["Jp", "Jt", "Jt"]

[[forces]]
repeat = {{ i = [1, "n - 1"] }}
type = "bushing"
bodies = ["b{{i}}", "b{{i + 1}}"]
at = ["i * h", 0.0, 0.0]
stiffness = ["k", "k", "k", "kt", "kr", "1.5 * kr"]

[[forces]]
type = "bushing"
bodies = ["ground", "b1"]
at = [0.0, 0.0, 0.0]
stiffness = ["k", "k", "k", "kt", "kr", "1.5 * kr"]

[[forces]]
type = "bushing"
bodies = ["ground", "b{n}"]
at = ["n * h", 0.0, 0.0]
stiffness = ["k", "k", "k", "kt", "kr", "1.5 * kr"]
"""



def _floor(text, mass, Jq):
    """tomllib on the case text, and M and Φ_q as CSR from their own triplets."""
    import scipy.sparse as sp

    t = time.perf_counter()
    tomllib.loads(text)
    for A in (mass.tocoo(), Jq.tocoo()):
        sp.csr_matrix((A.data, (A.row, A.col)), shape=A.shape)
    return time.perf_counter() - t


def build_chain(n, directory):
    """(model, {stage: seconds}) of one read and first assembly of the n-body chain."""
    from ..casefile import load_case

    path = Path(directory) / f"chain{n}.toml"
    path.write_text(CASE.format(n=n))
    times = {}
    t = time.perf_counter()
    model = load_case(path)
    times["read + assemble"] = time.perf_counter() - t
    q = model.q_init
    t = time.perf_counter()
    model.phi(q)
    Jq = model.phi_q(q)
    model.generalized_force(q)
    model.force_jacobians(q)
    times["first Φ, Φ_q, g, K, C"] = time.perf_counter() - t
    times["floor"] = _floor(path.read_text(), model.mass, Jq)
    return model, times


def bench_spatial(log=print, *, n=10_000, repeats=3):
    """The spatial section (module docstring): medians of ``repeats`` runs."""
    load = os.getloadavg()[0]
    runs = []
    with tempfile.TemporaryDirectory() as tmp:
        for _ in range(repeats):
            model, times = build_chain(n, tmp)
            runs.append(times)
    stages = {k: statistics.median(r[k] for r in runs) for k in runs[0]}
    total = statistics.median(r["read + assemble"] + r["first Φ, Φ_q, g, K, C"] for r in runs)
    log(f"spatial chain of {n} bodies: read + assemble {stages['read + assemble']:.2f} s, first "
        f"evaluation {stages['first Φ, Φ_q, g, K, C']:.2f} s, floor {stages['floor']:.2f} s "
        f"(median of {repeats}, load {load:.1f})")
    return [{"section": "spatial", "method": f"chain of {n} spatial bodies on bushings", "n": n,
             "coordinates": int(model.n), "time": total, "stages": stages,
             "floor": stages["floor"], "repeats": repeats, "load": load}]
