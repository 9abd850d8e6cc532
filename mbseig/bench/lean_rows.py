"""Rows of ``mbseig bench`` for lean flexible models (issue "Flexible models as lean as an FE
code"), section "lean", against the issue's goals:

- **multi-span shaft**, 10³ to 10⁵ degrees of freedom: steel, d = 50 mm, Euler–Bernoulli,
  SPANS spans of 1 m, 25 elements a span, universal joints to the ground at the SPANS + 1
  supports (translations and twist held).  The whole ``mbseig modes CASE --n-modes 20 --json``
  process against the FE floor, a whole script (:data:`FLOOR_SCRIPT`) that assembles the
  standard 6-DOF-per-node matrices of the same mesh with numpy, removes the held degrees of
  freedom and calls scipy's ``eigsh`` (shift-invert at 0) for the lowest 20: wall time and
  peak memory (each process's own ``ru_maxrss``), medians of ``repeats`` runs taken in turn;
  goal ≤ 2× both, and the 20 frequencies within 1e-8;
- **rotors**: a Campbell sweep of ROSS's example rotor (cases/ross_example_rotor.toml,
  51 speeds, 0–5000 rpm), of Friswell's ex. 5.9.1–5.9.3 (the same case with the larger second
  disk and their bearings, 41 speeds, 0–4000 rpm) and of Friswell's ex. 5.9.9
  (cases/overhung_rotor_friswell.toml, 41 speeds, 0–800 rad/s), mbseig's ``campbell`` (whirl,
  log decrement and critical speeds) against ROSS 2.3's ``run_campbell`` on the same rotor and
  speeds in its own interpreter (``MBSEIG_ROSS_PYTHON``), per speed; goal: no slower;
- **FE bodies**: a Timoshenko bar exported as a 3-D FE body (every internal mode kept), clamped
  at one end, a rigid tip body carried at the other; mbseig's frequencies from the case against
  34-digit ones (mpmath) of the assembled matrices (the FE body's with the tip's mass and
  inertia added at its node), and LAPACK's ``dsygvd`` (eigenvalues and vectors, the driver
  mbseig's eigh path calls) on the same assembled matrices; goal: mbseig's largest error within
  2× LAPACK's, as medians over :data:`FE_DRAWS` draws of the input's own rounding (both errors
  are rounding of a κ ≈ 1e9 problem: a single draw's ratio is a coin toss between 0.02 and 13).
"""

from __future__ import annotations

import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from .cases import case_path, load_average
from .rotor_rows import ROSS_FRISWELL_599

__all__ = ["FLOOR_SCRIPT", "bench_lean", "report_lines", "shaft_case"]

PER_SPAN = 25
SHAFT_SPANS = (7, 68, 685)  # 1,022, 9,928 and 100,010 degrees of freedom
EPS = np.finfo(float).eps

#: the FE floor: argv = spans, elements a span; prints the DOF and the 20 lowest ω [rad/s]
FLOOR_SCRIPT = r"""
import json, sys
import numpy as np, scipy.sparse as sp
from scipy.sparse.linalg import eigsh
spans, per = int(sys.argv[1]), int(sys.argv[2])
E, G, rho, d = 2.1e11, 8.1e10, 7800.0, 0.05
A = np.pi * d**2 / 4; I = np.pi * d**4 / 64; J = 2 * I
ne = spans * per; h = 1.0 / per; nn = ne + 1
k = np.zeros((12, 12)); m = np.zeros((12, 12))
def put(mat, idx, blk):
    mat[np.ix_(idx, idx)] += blk
bar = np.array([[1.0, -1.0], [-1.0, 1.0]]); lin = np.array([[2.0, 1.0], [1.0, 2.0]]) / 6
put(k, [0, 6], E * A / h * bar); put(k, [3, 9], G * J / h * bar)
put(m, [0, 6], rho * A * h * lin); put(m, [3, 9], rho * J * h * lin)
kb = E * I / h**3 * np.array([[12, 6*h, -12, 6*h], [6*h, 4*h*h, -6*h, 2*h*h],
                              [-12, -6*h, 12, -6*h], [6*h, 2*h*h, -6*h, 4*h*h]])
mb = rho * A * h / 420 * np.array([[156, 22*h, 54, -13*h], [22*h, 4*h*h, 13*h, -3*h*h],
                                   [54, 13*h, 156, -22*h], [-13*h, -3*h*h, -22*h, 4*h*h]])
S = np.diag([1.0, -1.0, 1.0, -1.0])
put(k, [1, 5, 7, 11], kb); put(m, [1, 5, 7, 11], mb)
put(k, [2, 4, 8, 10], S @ kb @ S); put(m, [2, 4, 8, 10], S @ mb @ S)
dofs = (6 * np.arange(ne))[:, None] + np.arange(12)[None, :]
rows = np.repeat(dofs, 12, axis=1).ravel(); cols = np.tile(dofs, (1, 12)).ravel()
K = sp.csr_matrix((np.tile(k.ravel(), ne), (rows, cols)), shape=(6 * nn, 6 * nn))
M = sp.csr_matrix((np.tile(m.ravel(), ne), (rows, cols)), shape=(6 * nn, 6 * nn))
held = ((6 * per * np.arange(spans + 1))[:, None] + np.arange(4)[None, :]).ravel()
keep = np.setdiff1d(np.arange(6 * nn), held)
K = K[keep][:, keep].tocsc(); M = M[keep][:, keep].tocsc()
w2 = eigsh(K, 20, M, sigma=0, which="LM", return_eigenvectors=False)
print(json.dumps({"dof": int(K.shape[0]), "omega": np.sqrt(np.sort(w2)).tolist()}))
"""

#: runs a script or ``-m module`` with its arguments, then writes its own peak RSS [kB] to the
#: file named by MBSEIG_RSS_FILE (each process measures itself: no psutil needed)
_RSS_WRAPPER = r"""
import os, resource, runpy, sys
out = os.environ["MBSEIG_RSS_FILE"]
def _done():
    with open(out, "w") as fh:
        fh.write(str(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss))
import atexit; atexit.register(_done)
_exit = os._exit
def _ended(code):  # (mbseig's command line ends by os._exit: no atexit there)
    _done()
    _exit(code)
os._exit = _ended
if sys.argv[1] == "-m":
    sys.argv = sys.argv[2:]
    runpy.run_module(sys.argv[0], run_name="__main__", alter_sys=True)
else:
    sys.argv = sys.argv[1:]
    runpy.run_path(sys.argv[0], run_name="__main__")
"""


def shaft_case(spans, per=PER_SPAN) -> str:
    """The multi-span shaft as a case file (module docstring)."""
    stations = ", ".join(f"s{k} = {float(k)}" for k in range(spans + 1))
    text = [f'''schema_version = 1
title = "Multi-span shaft: {spans} spans of 1 m on universal joints"
dimension = 3
[parameters]
E = 2.1e11
G = 8.1e10
rho = 7800.0
[[points]]
name = "start"
position = [0.0, 0.0, 0.0]
[[points]]
name = "end"
position = [{float(spans)}, 0.0, 0.0]
[[beams]]
name = "shaft"
points = ["start", "end"]
E = "E"
G = "G"
rho = "rho"
section = {{ shape = "circle", d = 0.05 }}
elements = {spans * per}
ends = ["free", "free"]
stations = {{ {stations} }}
''']
    for k in range(spans + 1):
        text.append(f'''[[joints]]
name = "support {k}"
type = "universal"
bodies = ["ground", "shaft.s{k}"]
at = [{float(k)}, 0.0, 0.0]
axes = [[0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
''')
    return "\n".join(text)


def _timed(args, tmp):
    """(wall seconds, peak RSS [MB], stdout) of one process run through the RSS wrapper."""
    rss = Path(tmp) / "rss.txt"
    env = {**os.environ, "MBSEIG_RSS_FILE": str(rss), "OMP_NUM_THREADS": "1",
           "OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}
    t = time.perf_counter()
    out = subprocess.run([sys.executable, "-c", _RSS_WRAPPER, *args], capture_output=True,
                         text=True, env=env, check=False)
    wall = time.perf_counter() - t
    if out.returncode != 0:
        raise RuntimeError((out.stderr.strip().splitlines() or ["no output"])[-1][:200])
    return wall, int(rss.read_text()) / 1024.0, out.stdout


def _shaft_rows(spans_list, repeats, log):
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        floor = Path(tmp) / "floor.py"
        floor.write_text(FLOOR_SCRIPT)
        for spans in spans_list:
            case = Path(tmp) / f"shaft_{spans}.toml"
            case.write_text(shaft_case(spans))
            ours, theirs = [], []
            for _ in range(repeats):  # in turn, so that the machine's load falls on both
                t, m, out = _timed(["-m", "mbseig", "modes", str(case), "--n-modes", "20",
                                    "--json"], tmp)
                ours.append((t, m, out))
                t, m, out = _timed([str(floor), str(spans), str(PER_SPAN)], tmp)
                theirs.append((t, m, out))
            w = np.sort([md["omega_n"] for md in json.loads(ours[-1][2])["modes"]])
            fl = json.loads(theirs[-1][2].strip().splitlines()[-1])
            wf = np.asarray(fl["omega"])
            agree = float(np.max(np.abs(w / wf - 1))) if w.size == wf.size else float("nan")
            t1, m1 = (statistics.median(x[k] for x in ours) for k in (0, 1))
            t0, m0 = (statistics.median(x[k] for x in theirs) for k in (0, 1))
            row = {"section": "lean", "method": "multi-span shaft", "n": fl["dof"],
                   "spans": spans, "time": t1, "rss_mb": m1, "floor_time": t0,
                   "floor_rss_mb": m0, "time_ratio": t1 / t0, "rss_ratio": m1 / m0,
                   "agreement": agree, "repeats": repeats,
                   "spread": [min(x[0] for x in ours) / t1, max(x[0] for x in ours) / t1],
                   "goal": "≤ 2× time and memory, agreement ≤ 1e-8",
                   "met": bool(t1 <= 2 * t0 and m1 <= 2 * m0 and agree <= 1e-8)}
            rows.append(row)
            log(f"lean shaft {spans} spans ({fl['dof']} DOF): mbseig {t1:.2f} s {m1:.0f} MB, "
                f"floor {t0:.2f} s {m0:.0f} MB ({t1 / t0:.2f}×, {m1 / m0:.2f}×), "
                f"agreement {agree:.1e}")
    return rows


#: run by the ROSS interpreter: argv = rotor (a key of ``makers``), repeats, speeds [rad/s]
ROSS_CAMPBELL = r"""
import json, sys, time, warnings
warnings.simplefilter("ignore")
import numpy as np
import ross as rs
which, repeats = sys.argv[1], int(sys.argv[2])
speeds = np.array([float(x) for x in sys.argv[3:]])
""" + ROSS_FRISWELL_599 + r"""
def friswell_59(kyy):  # ex. 5.9.1-5.9.3: two disks, bearings kxx = 1 MN/m and kyy
    steel = rs.Material(name="Steel", rho=7810, E=211e9, G_s=81.2e9)
    shaft = [rs.ShaftElement(L=0.25, idl=0.0, odl=0.05, material=steel, shear_effects=True,
                             rotary_inertia=True, gyroscopic=True) for _ in range(6)]
    disks = [rs.DiskElement.from_geometry(n=2, material=steel, width=0.07, i_d=0.05, o_d=0.28),
             rs.DiskElement.from_geometry(n=4, material=steel, width=0.07, i_d=0.05, o_d=0.35)]
    bearings = [rs.BearingElement(n=0, kxx=1e6, kyy=kyy, cxx=0.0),
                rs.BearingElement(n=6, kxx=1e6, kyy=kyy, cxx=0.0)]
    return rs.Rotor(shaft, disks, bearings)
makers = {"example": rs.rotor_example, "friswell_5_9_9": friswell,
          "friswell_5_9_1": lambda: friswell_59(1e6), "friswell_5_9_2": lambda: friswell_59(0.8e6),
          "friswell_5_9_3": lambda: friswell_59(0.2e6)}
make = makers[which]
make().run_campbell(speeds[:2])  # (warm: imports and compilation)
times = []
for _ in range(repeats):
    t = time.perf_counter()
    make().run_campbell(speeds)
    times.append(time.perf_counter() - t)
print(json.dumps({"times": times}))
"""

#: Friswell's ex. 5.9.1-5.9.3 on cases/ross_example_rotor.toml: the larger second disk
_BIG_DISK = {"m_disk1": 51.5252611115262, "Id1": 0.42358058405433824,
             "Ip1": 0.8050822048675967}
_RPM4000 = np.linspace(0.0, 4000 * np.pi / 30, 41)
#: (label, case, fixed parameters, ROSS's builder, speeds [rad/s])
ROTORS = (("ROSS's example rotor (rotor_example)", "ross_example_rotor", {}, "example",
           np.linspace(0.0, 5000 * np.pi / 30, 51)),
          ("Friswell ex. 5.9.1 (isotropic bearings)", "ross_example_rotor",
           {**_BIG_DISK, "kzz": 1e6}, "friswell_5_9_1", _RPM4000),
          ("Friswell ex. 5.9.2 (anisotropic bearings)", "ross_example_rotor",
           {**_BIG_DISK, "kzz": 0.8e6}, "friswell_5_9_2", _RPM4000),
          ("Friswell ex. 5.9.3 (mixed modes)", "ross_example_rotor",
           {**_BIG_DISK, "kzz": 0.2e6}, "friswell_5_9_3", _RPM4000),
          ("Friswell ex. 5.9.9 (overhung)", "overhung_rotor_friswell", {}, "friswell_5_9_9",
           np.linspace(0.0, 800.0, 41)))


def _rotor_rows(repeats, log, ross_python):
    from ..casefile import read_case
    from ..numerics import blas_limit
    from ..studies.campbell import campbell

    rows = []
    for label, case, fixed, which, speeds in ROTORS:
        spec = read_case(case_path(case))
        with blas_limit(1):
            campbell(spec, "Omega", speeds[:3], fixed=fixed)  # (warm)
            times = []
            for _ in range(repeats):
                t = time.perf_counter()
                res = campbell(spec, "Omega", speeds, fixed=fixed)
                times.append(time.perf_counter() - t)
        per = statistics.median(times) / speeds.size
        ross, why = None, "no ROSS interpreter (MBSEIG_ROSS_PYTHON)"
        if ross_python:
            env = {**os.environ, "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1"}
            out = subprocess.run([ross_python, "-c", ROSS_CAMPBELL, which, str(repeats),
                                  *map(repr, map(float, speeds))], capture_output=True,
                                 text=True, env=env, check=False, timeout=1800)
            if out.returncode == 0:
                ross = statistics.median(json.loads(out.stdout.strip().splitlines()[-1])
                                         ["times"]) / speeds.size
            else:
                why = (out.stderr.strip().splitlines() or ["no output"])[-1][:120]
        row = {"section": "lean", "method": f"Campbell sweep, {label}", "n": int(speeds.size),
               "time": per * speeds.size, "per_speed": per, "ross_per_speed": ross,
               "reuse": res.reuse, "critical_speeds": [round(c["value"], 3)
                                                       for c in res.critical_speeds],
               "repeats": repeats, "goal": "per speed ≤ ROSS's run_campbell",
               "met": None if ross is None else bool(per <= ross),
               "note": "" if ross is not None else why}
        rows.append(row)
        log(f"lean Campbell {label}: mbseig {per * 1e3:.1f} ms a speed ({res.reuse}); ROSS "
            + (f"{ross * 1e3:.1f} ms a speed" if ross is not None else f"not run: {why}"))
    return rows


FE_MODELS = ((6, 2.0), (8, 0.5), (10, 2.0), (12, 5.0))  # (elements of the bar, tip mass [kg])
TIP_INERTIA = (0.01, 0.02, 0.03)
#: draws of each FE model: as exported, then with every entry of K moved by its own rounding
#: (relative 2e-16 N(0, 1), symmetric).  Both errors are rounding of a problem with κ ≈ 1e9, and
#: one draw's ratio of them ranged 0.02–13 over such draws (measured at 3ba5cb0): the row
#: compares the medians of the draws, and shows the as-exported draw beside them.
FE_DRAWS = 8
FE_JITTER = 2e-16


def _fe_rows(log):
    try:
        import mpmath as mp
    except ImportError:  # (the test extra has it; a plain install may not)
        log("lean FE bodies not run: their 34-digit references need mpmath (pip install mpmath)")
        return []
    import scipy.linalg as sla

    import mbseig

    from ..model.fe_body import export_fe_body

    mp.mp.dps = 34
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        for nel, m_tip in FE_MODELS:
            (tmp / "free.toml").write_text(_FREE_BAR.format(nel=nel))
            export_fe_body(mbseig.load_case(tmp / "free.toml"), ["A", "B"], tmp / "bar0.npz")
            exported = dict(np.load(tmp / "bar0.npz"))
            (tmp / "fe.toml").write_text(_FE_CASE.format(m=m_tip, inertia=list(TIP_INERTIA)))
            draws = []
            for seed in range(FE_DRAWS):
                K0 = exported["K"]
                if seed:
                    E = np.random.default_rng(seed).standard_normal(K0.shape)
                    K0 = K0 * (1.0 + FE_JITTER * 0.5 * (E + E.T))
                np.savez(tmp / "bar.npz", **{**exported, "K": K0})
                a = mbseig.analyze(tmp / "fe.toml")
                draws.append(_fe_errors(mp, sla, np.sort(a.modes.omega_n), exported["M"], K0,
                                        m_tip))
            e_mb, e_la = (np.array([d[k] for d in draws]) for k in (0, 1))
            med_mb, med_la = float(np.median(e_mb)), float(np.median(e_la))
            rows.append({"section": "lean", "method": "FE body with a tip body",
                         "n": int(exported["M"].shape[0] - 6), "elements": nel,
                         "tip_mass": m_tip, "time": float("nan"), "draws": FE_DRAWS,
                         "error": med_mb, "lapack_error": med_la, "ratio": med_mb / med_la,
                         "exported_error": float(e_mb[0]),
                         "exported_lapack_error": float(e_la[0]),
                         "draw_ratios": [float(x) for x in e_mb / e_la],
                         "goal": "median largest error ≤ 2× LAPACK's",
                         "met": bool(med_mb <= 2 * med_la),
                         "basis": a.linear.tolerances.get("basis", "global")})
            log(f"lean FE body {nel} el, tip {m_tip} kg ({rows[-1]['n']} DOF): median largest "
                f"error over {FE_DRAWS} draws mbseig {med_mb:.1e}, LAPACK {med_la:.1e}; as "
                f"exported {e_mb[0]:.1e} and {e_la[0]:.1e}")
    return rows


def _fe_errors(mp, sla, w_mb, M, K, m_tip):
    """(mbseig's, LAPACK's) largest relative error of the clamped FE body with its tip body,
    against the 34-digit eigenvalues of the same matrices (mpmath)."""
    M = M.copy()
    M[6:9, 6:9] += m_tip * np.eye(3)
    M[9:12, 9:12] += np.diag(TIP_INERTIA)
    keep = np.arange(6, M.shape[0])  # A clamped
    M, K = M[np.ix_(keep, keep)], K[np.ix_(keep, keep)]
    Li = mp.inverse(mp.cholesky(mp.matrix(M.tolist())))
    C = Li * mp.matrix(K.tolist()) * Li.T
    ref = np.sort([float(mp.sqrt(x)) for x in mp.eigsy((C + C.T) / 2, eigvals_only=True)])
    w, _, _ = sla.lapack.dsygvd(0.5 * (K + K.T), 0.5 * (M + M.T), itype=1, jobz="V", uplo="L")
    w_la = np.sqrt(np.sort(w))
    return float(np.max(np.abs(w_mb / ref - 1))), float(np.max(np.abs(w_la / ref - 1)))


_FREE_BAR = """
schema_version = 1
dimension = 3
[[points]]
name = "A"
position = [0.0, 0.0, 0.0]
[[points]]
name = "B"
position = [1.0, 0.0, 0.0]
[[beams]]
name = "beam"
points = ["A", "B"]
E = 2.1e11
G = 8.1e10
rho = 7850
section = {{ shape = "rectangle", b = 0.03, h = 0.02 }}
orientation = [0.0, 1.0, 0.0]
theory = "timoshenko"
elements = {nel}
ends = ["free", "free"]
"""
_FE_CASE = """
schema_version = 1
dimension = 3
[[points]]
name = "A"
position = [0.0, 0.0, 0.0]
fixed = true
[[points]]
name = "B"
position = [1.0, 0.0, 0.0]
[[bodies]]
name = "tip"
mass = {m}
com = [1.0, 0.0, 0.0]
inertia = {inertia}
points = ["B"]
[[fe_bodies]]
name = "bar"
mass = {{file = "bar.npz", key = "M"}}
stiffness = {{file = "bar.npz", key = "K"}}
interface = ["A", "B"]
rotations = ["clamped", "tip"]
"""


def bench_lean(log, *, repeats=3, quick=False, ross_python=None):
    """The rows (module docstring)."""
    load0 = load_average()
    rows = _shaft_rows(SHAFT_SPANS[:2] if quick else SHAFT_SPANS, repeats, log)
    rows += _rotor_rows(repeats, log, ross_python or os.environ.get("MBSEIG_ROSS_PYTHON"))
    rows += _fe_rows(log)
    load1 = load_average()
    for r in rows:
        r["load"] = {"start": load0, "end": load1}
    return rows


def report_lines(rows) -> list:
    """The Markdown section of the rows."""
    if not rows:
        return []
    r0 = rows[0]
    L = ["", "## Lean flexible models", "",
         "One BLAS thread. Load average before and after: "
         f"{r0['load']['start']} → {r0['load']['end']}.", "",
         "| row | size | mbseig | floor / peer | ratio | other | goal | met |",
         "|---|---|---|---|---|---|---|---|"]
    for r in rows:
        met = "–" if r["met"] is None else ("yes" if r["met"] else "**no**")
        if r["method"] == "multi-span shaft":
            L.append(f"| shaft, {r['spans']} spans | {r['n']:,} DOF | {r['time']:.2f} s, "
                     f"{r['rss_mb']:.0f} MB | FE floor {r['floor_time']:.2f} s, "
                     f"{r['floor_rss_mb']:.0f} MB | {r['time_ratio']:.2f}× time, "
                     f"{r['rss_ratio']:.2f}× memory | agreement {r['agreement']:.1e}; spread "
                     "{:.2f}–{:.2f}, {} runs".format(*r["spread"], r["repeats"])
                     + f" | {r['goal']} | {met} |")
        elif "per_speed" in r:
            ross = (f"ROSS run_campbell {r['ross_per_speed'] * 1e3:.1f} ms a speed"
                    if r["ross_per_speed"] is not None else f"ROSS not run ({r['note']})")
            ratio = (f"{r['per_speed'] / r['ross_per_speed']:.2f}×"
                     if r["ross_per_speed"] is not None else "–")
            L.append(f"| {r['method']} | {r['n']} speeds | {r['per_speed'] * 1e3:.1f} ms a "
                     f"speed | {ross} | {ratio} | {r['reuse']}; critical speeds "
                     f"{r['critical_speeds']} rad/s | {r['goal']} | {met} |")
        else:
            spread = "{:.2f}–{:.2f}".format(min(r["draw_ratios"]), max(r["draw_ratios"]))
            L.append(f"| FE body, {r['elements']} elements, tip {r['tip_mass']} kg | {r['n']} "
                     f"DOF | median largest error {r['error']:.1e} ({r['draws']} draws; as "
                     f"exported {r['exported_error']:.1e}) | LAPACK dsygvd "
                     f"{r['lapack_error']:.1e} (as exported {r['exported_lapack_error']:.1e}) | "
                     f"{r['ratio']:.2f}× | a draw's ratio {spread}; 34-digit reference (mpmath); "
                     f"basis {r['basis']} | {r['goal']} | {met} |")
    return L
