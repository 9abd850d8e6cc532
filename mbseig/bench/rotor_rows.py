"""Rows of the ``mbseig bench`` report for flexible rotors: a Campbell diagram of 41 speeds of
Friswell's overhung rotor (cases/overhung_rotor_friswell.toml, ex. 5.9.9, 6 Timoshenko
elements), timed, and its agreement with ROSS 2.3.0 at the same mesh; ROSS's own time for the
same diagram where a Python with ROSS is given.

ROSS (ross-rotordynamics 2.3, Python 3.11 with ``plotly<6``) does not install beside mbseig's
dependencies, so it runs in its own interpreter: ``MBSEIG_ROSS_PYTHON=/path/to/python`` (or
``ross_python=``) runs :data:`ROSS_SCRIPT` there, which builds the same rotor (ROSS's
``ShaftElement``, ``DiskElement.from_geometry``, ``BearingElement``) and times ``run_campbell``
over the same speeds.  Without it the ROSS columns say so.  The agreement (eigenvalues with
|s| > 0.1 at 0 and 4000 rpm, every stored ROSS eigenvalue against its nearest mbseig one) uses
the ROSS eigenvalues stored in tests/data/ross/friswell_lateral.json.

Row keys: ``section`` "rotor", ``method``, ``n`` (speeds), ``time`` (median wall seconds of
``repeats`` runs), ``per_speed``, ``error`` (largest relative eigenvalue difference to ROSS, or
NaN), ``repeats``, ``load`` (1-minute load average at the start), ``note``.
"""

from __future__ import annotations

import json
import math
import os
import statistics
import subprocess
import time
from pathlib import Path

import numpy as np

__all__ = ["ROSS_SCRIPT", "bench_rotor"]

ROOT = Path(__file__).resolve().parents[2]
CASE = ROOT / "cases" / "overhung_rotor_friswell.toml"
STORED = ROOT / "tests" / "data" / "ross" / "friswell_lateral.json"

#: Friswell's ex. 5.9.9 as ROSS builds it (``friswell()``), for the scripts the ROSS
#: interpreter runs (this module's and :mod:`mbseig.bench.lean_rows`')
ROSS_FRISWELL_599 = """
def friswell():
    steel = rs.Material(name="steel_friswell", rho=7810, E=211e9, G_s=81.2e9)
    shaft = [rs.ShaftElement(L=0.25, idl=0.0, odl=0.05, material=steel, shear_effects=True,
                             rotary_inertia=True, gyroscopic=True) for _ in range(6)]
    disk = rs.DiskElement.from_geometry(n=6, material=steel, width=0.07, i_d=0.05, o_d=0.35)
    bearings = [rs.BearingElement(n=0, kxx=1e7, kyy=1e7, cxx=0.0),
                rs.BearingElement(n=4, kxx=1e7, kyy=1e7, cxx=0.0)]
    return rs.Rotor(shaft, [disk], bearings)
"""

#: run by the ROSS interpreter: argv = [speeds..., repeats]; prints {"times": [...]}
ROSS_SCRIPT = """
import json, sys, time, warnings
warnings.simplefilter("ignore")
import numpy as np
import ross as rs
speeds = np.array([float(x) for x in sys.argv[1:-1]]); repeats = int(sys.argv[-1])
""" + ROSS_FRISWELL_599 + """
times = []
for _ in range(repeats):
    t = time.perf_counter()
    friswell().run_campbell(speeds, frequencies=6)
    times.append(time.perf_counter() - t)
print(json.dumps({"times": times}))
"""


def _ross_times(python, speeds, repeats, timeout):
    out = subprocess.run([python, "-c", ROSS_SCRIPT, *map(repr, map(float, speeds)), str(repeats)],
                         capture_output=True, text=True, timeout=timeout, check=False)
    if out.returncode != 0:
        return None, (out.stderr.strip().splitlines() or ["no output"])[-1][:120]
    return json.loads(out.stdout.strip().splitlines()[-1])["times"], ""


def _ross_agreement():
    """Largest relative distance of a stored ROSS eigenvalue (Friswell 5.9.1–5.9.3, 6 elements,
    0 and 418.879 rad/s) to mbseig's nearest, per example."""
    import importlib.util

    spec = importlib.util.spec_from_file_location("ross_friswell",
                                                  ROOT / "benchmarks" / "ross_friswell.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    data = json.loads(STORED.read_text())["examples"]
    out = {}
    for ex, v in data.items():
        errs = []
        for speed, s in v["speeds"].items():
            ross = np.array([complex(a, b) for a, b in s])
            ours, _, _ = mod.mbseig_eigenvalues(v["model"], float(speed))
            errs.append(mod.compare(ross, ours))
        out[ex] = max(errs)
    return out


def bench_rotor(log=print, *, n_speeds=41, top=800.0, repeats=3, ross_python=None,
                timeout=900.0):
    """Rows of the rotor section (module docstring): the Campbell diagram of the overhung rotor
    over Ω = 0 … ``top`` rad/s at ``n_speeds`` speeds in mbseig (one process) and, when a ROSS
    interpreter is given, in ROSS; the stored ROSS agreement of Friswell's 5.9.1–5.9.3."""
    from ..casefile import read_case
    from ..numerics import blas_limit
    from ..studies.campbell import campbell

    load = os.getloadavg()[0]
    speeds = np.linspace(0.0, top, n_speeds)
    spec = read_case(CASE)
    times = []
    with blas_limit(1):
        for _ in range(repeats):
            t = time.perf_counter()
            res = campbell(spec, "Omega", speeds)
            times.append(time.perf_counter() - t)
    med = statistics.median(times)
    crit = ", ".join(f"{c['value']:.1f} ({c['whirl']})" for c in res.critical_speeds[:4])
    rows = [{"section": "rotor", "method": "mbseig campbell (whirl, log dec, critical speeds)",
             "n": n_speeds, "time": med, "per_speed": med / n_speeds, "error": math.nan,
             "repeats": repeats, "load": load, "note": f"critical speeds [rad/s]: {crit}"}]
    log(f"rotor Campbell, {n_speeds} speeds, mbseig: {med:.2f} s ({med / n_speeds * 1e3:.0f} ms "
        f"per speed, median of {repeats}, load {load:.1f})")
    python = ross_python or os.environ.get("MBSEIG_ROSS_PYTHON")
    if python:
        rt, why = _ross_times(python, speeds, repeats, timeout)
    else:
        rt, why = None, "no ROSS interpreter (MBSEIG_ROSS_PYTHON)"
    if rt:
        rmed = statistics.median(rt)
        rows.append({"section": "rotor", "method": "ROSS 2.3 run_campbell", "n": n_speeds,
                     "time": rmed, "per_speed": rmed / n_speeds, "error": math.nan,
                     "repeats": repeats, "load": load, "note": "same rotor, same mesh"})
        log(f"rotor Campbell, {n_speeds} speeds, ROSS: {rmed:.2f} s")
    else:
        log(f"rotor Campbell, ROSS not run: {why}")
    for ex, err in _ross_agreement().items():
        rows.append({"section": "rotor", "method": f"agreement with ROSS: {ex}", "n": 2,
                     "time": math.nan, "per_speed": math.nan, "error": err, "repeats": 1,
                     "load": load, "note": "eigenvalues |s| > 0.1, 0 and 418.879 rad/s"})
        log(f"ROSS agreement {ex}: {err:.1e}")
    return rows
