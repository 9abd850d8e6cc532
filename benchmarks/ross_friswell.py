"""Friswell's example rotors (Dynamics of Rotating Machines, 2010, examples 5.9.x) in mbseig and in
ROSS 2.3.0, same mesh, side by side: eigenvalues, log decrements, time per speed.

The rotors are those ROSS's tests build (``ross/tests/test_examples.py``); their model data
(every shaft element, disk and bearing) and ROSS's eigenvalues come from the stored ROSS runs
(friswell_rotors.json and friswell_rotors_eig.npz in the folder MBSEIG_ROSS_DATA, made by its
scripts/02_friswell_rotors.py), or from tests/data/ross/friswell_lateral.json (a subset).  Each
rotor becomes a ``dimension = 3`` mbseig case: the shaft a Timoshenko ``[[beams]]`` along x
with a station at every ROSS node (ROSS's axis z is mbseig's x; its (x, y) are mbseig's (y, z),
a cyclic relabelling that keeps the spin sense), each disk a body welded to its station with a
``rotor`` force, each bearing a ``bushing`` to the ground (kxx, kyy, kxy, kyx → the y, z block).

ROSS leaves the axial and torsional rigid-body motions free (its bearings act on x, y, z only,
kzz = 0) and drops |λ| < 0.1; mbseig lists them as zero eigenvalues: both are compared on the
eigenvalues with |λ| > 0.1 (lateral modes and the torsional mode at 650.4 rad/s).

    python benchmarks/ross_friswell.py             # every stored 6-element rotor, all speeds
    python benchmarks/ross_friswell.py --extract   # rewrite tests/data/ross/friswell_lateral.json
    python benchmarks/ross_friswell.py --ross      # also print ROSS's stored wall times
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

import numpy as np

# a folder written by a ROSS run (friswell_rotors.json, friswell_rotors_eig.npz: ROSS 2.3 on
# Python 3.11 with plotly<6), given by MBSEIG_ROSS_DATA; without it the stored numbers are used
RESEARCH = Path(os.environ["MBSEIG_ROSS_DATA"]) if os.environ.get("MBSEIG_ROSS_DATA") else None
STORED = Path(__file__).resolve().parents[1] / "tests" / "data" / "ross" / "friswell_lateral.json"
EXAMPLES = ("ex1_friswell_5_9_1_nel6", "ex3_friswell_5_9_2_nel6", "ex5_friswell_5_9_3_nel6",
            "ex4_friswell_5_9_5_damped_nel6", "ex2_friswell_5_9_9_overhung_nel6")
MIN_ABS = 0.1  # ROSS drops eigenvalues below this (rad/s)


def case_data(model: dict, speed: float) -> dict:
    """The mbseig case (a dict with the TOML structure) of one ROSS rotor model."""
    els = model["shaft_elements"]
    pos = model["nodes_pos"]
    first = els[0]
    mat = first["material"]
    for e in els:  # the conversion handles uniform cylindrical shafts (all of Friswell's 5.9.x)
        if (e["odl"], e["idl"], e["odr"], e["idr"]) != (first["odl"], first["idl"], first["odl"],
                                                        first["idl"]):
            raise ValueError("only uniform shafts are converted")
    section = ({"shape": "circle", "d": first["odl"]} if first["idl"] == 0 else
               {"shape": "tube", "d": first["odl"], "d_inner": first["idl"]})
    stations = {f"n{k}x": float(z - pos[0]) for k, z in enumerate(pos)}
    data = {
        "schema_version": 1, "title": "friswell", "dimension": 3,
        "parameters": {"Omega": float(speed)},
        "points": [{"name": "start", "position": [pos[0], 0.0, 0.0]},
                   {"name": "end", "position": [pos[-1], 0.0, 0.0]}],
        "beams": [{"name": "shaft", "points": ["start", "end"], "E": mat["E"], "G": mat["G_s"],
                   "rho": mat["rho"], "section": section,
                   "theory": "timoshenko" if first["shear_effects"] else "euler-bernoulli",
                   "elements": len(els), "ends": ["free", "free"], "stations": stations,
                   "spin": "Omega"}],
        "bodies": [], "joints": [], "forces": [],
    }
    for k, d in enumerate(model.get("disk_elements", [])):
        name = f"disk{k + 1}"
        x = float(pos[d["n"]])
        data["bodies"].append({"name": name, "mass": d["m"], "com": [x, 0.0, 0.0],
                               "inertia": [d["Ip"], d["Id"], d["Id"]]})
        data["joints"].append({"name": f"{name} fit", "type": "weld",
                               "bodies": [f"shaft.n{d['n']}x", name], "at": [x, 0.0, 0.0]})
        data["forces"].append({"name": f"{name} spin", "type": "rotor", "body": name,
                               "axis": [1.0, 0.0, 0.0], "polar_inertia": d["Ip"],
                               "speed": "Omega"})
    for k, b in enumerate(model.get("bearing_elements", [])):
        K, C = np.zeros((6, 6)), np.zeros((6, 6))
        for M, p in ((K, "k"), (C, "c")):
            M[0, 0] = b[f"{p}zz"]
            M[1, 1], M[1, 2] = b[f"{p}xx"], b[f"{p}xy"]
            M[2, 1], M[2, 2] = b[f"{p}yx"], b[f"{p}yy"]
        data["forces"].append({"name": f"bearing {k + 1}", "type": "bushing",
                               "bodies": ["ground", f"shaft.n{b['n']}x"],
                               "stiffness": K.tolist(), "damping": C.tolist()})
    return data


def mbseig_eigenvalues(model: dict, speed: float):
    """(eigenvalues with Im ≥ 0 and |λ| > MIN_ABS, whirl per eigenvalue, seconds)."""
    from mbseig import equilibrium, linearize, modes
    from mbseig.casefile import read_case
    from mbseig.model.spatial_whirl import whirl

    t = time.perf_counter()
    m = read_case(case_data(model, speed)).build()
    eq = equilibrium(m)
    md = modes(linearize(m, eq))
    seconds = time.perf_counter() - t
    s = np.asarray(md.eigenvalues)
    keep = np.abs(s) > MIN_ABS
    w = [whirl(m, eq.q, md.shapes[:, k], s[k]) for k in np.flatnonzero(keep)]
    return s[keep], w, seconds


def compare(ross: np.ndarray, ours: np.ndarray) -> float:
    """Largest relative distance from a ROSS eigenvalue (Im > 0, |λ| > MIN_ABS) to mbseig's."""
    ref = ross[(ross.imag > 0) & (np.abs(ross) > MIN_ABS)]
    return max(float(np.min(np.abs(ours - r)) / abs(r)) for r in ref)


def stored():
    """{example: {"model", "speeds": {speed: [[re, im], ...]}}} from the research data."""
    rot = json.loads((RESEARCH / "friswell_rotors.json").read_text())["models"]
    eig = np.load(RESEARCH / "friswell_rotors_eig.npz")
    out = {}
    for ex in EXAMPLES:
        speeds = {}
        for sp in rot[ex]["speeds"]:
            key = next(k for k in eig.files if k.startswith(f"{ex}__speed_")
                       and abs(float(k.split("_speed_")[1]) - float(sp)) < 1e-6)
            s = eig[key]
            s = s[(s.imag > 0) & (np.abs(s) > MIN_ABS)]
            speeds[sp] = [[float(x.real), float(x.imag)] for x in s]
        out[ex] = {"description": rot[ex]["description"], "model": rot[ex]["model"],
                   "speeds": speeds}
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--extract", action="store_true", help="rewrite the tests' stored subset")
    ap.add_argument("--ross", action="store_true", help="also print ROSS's stored wall times")
    args = ap.parse_args(argv)
    data = stored() if RESEARCH is not None and RESEARCH.exists() else json.loads(STORED.read_text())["examples"]
    if args.extract:
        keep = {ex: {**v, "speeds": {k: s for k, s in v["speeds"].items()
                                     if float(k) in (0.0, 418.879020478639)}}
                for ex, v in data.items() if ex in EXAMPLES[:3]}
        STORED.write_text(json.dumps({
            "source": "ROSS 2.3.0 (ross-rotordynamics), Friswell et al. 2010 examples as "
                      "ross/tests/test_examples.py builds them; eigenvalues: dense "
                      "scipy.linalg.eig of ROSS's state matrix (research scripts "
                      "02_friswell_rotors.py); Im > 0, |s| > 0.1",
            "examples": keep}, indent=1))
        print(f"wrote {STORED}")
        return 0
    print(f"{'rotor':36s} {'speed':>9s} {'max rel diff':>13s} {'mbseig s':>9s}")
    for ex, v in data.items():
        for sp, s in v["speeds"].items():
            ross = np.array([complex(a, b) for a, b in s])
            ours, _, sec = mbseig_eigenvalues(v["model"], float(sp))
            print(f"{ex:36s} {float(sp):9.3f} {compare(ross, ours):13.2e} {sec:9.3f}")
    if args.ross and RESEARCH is not None and RESEARCH.exists():  # ROSS's own timing, stored by its research run
        models = json.loads((RESEARCH / "friswell_rotors.json").read_text())["models"]
        for ex in EXAMPLES:
            print(f"{ex:36s} ROSS wall time (model + 5 speeds, modal post-processing included): "
                  f"{models[ex].get('wall_time_s')}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
