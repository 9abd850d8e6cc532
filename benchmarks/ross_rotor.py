"""Benchmark: the rigid rotor of cases/rigid_rotor.toml in mbseig and in ROSS, side by side.

ROSS (ross-rotordynamics, https://github.com/petrobras/ross) is a finite-element rotordynamics
package: 6 DOF per node, rotor axis z.  It has no rigid body, so the rigid rotor is a shaft of
very high Young's modulus (two Timoshenko elements of length a, negligible density) carrying a
disc (m, I_d = I_t, I_p = J_p) at the middle node, on two bearing elements (kxx, kyy lateral,
kzz axial at the first).  Axes: mbseig's (x, y, z) are ROSS's (z, x, y) (a cyclic permutation,
right-handed), so mbseig's ky, kz are ROSS's kxx, kyy.

    pip install ross-rotordynamics "plotly<6"     # ROSS 2.3.0 on Python 3.11 needs plotly 5
    python benchmarks/ross_rotor.py

Differences, and why (printed below with the numbers):
- modelling: the shaft of E = 1e17 Pa adds a flexibility of ~1e-7 relative to the bearings
  (its bending stiffness 48EI/L³ ≈ 7e12 N/m against 1e6 N/m), so ROSS's frequencies differ by
  ~1e-7 from the rigid-body closed form; mbseig's rigid body matches the closed form to 1e-14;
- numerics: ROSS's dense solver (``sparse=False``) works on the first-order state matrix,
  whose largest eigenvalues are the shaft's (~1e11 rad/s at E = 1e17): rounding then costs
  ε·ω_max²/ω ≈ 1e-3 relative on the bearing modes (and a spurious 0.5 rad/s torsional mode),
  so a stiffer "rigid" shaft is less accurate.  Its shift-invert path (``sparse=True``) does not
  suffer from it; mbseig has no such modes at all;
- whirl: ROSS calls an orbit forward when κ > 0 and backward otherwise, so a straight-line
  orbit (κ = 0 up to rounding: the cylindrical modes of this symmetric rotor) gets the sign of a
  rounding residue, and its sparse path's less accurate shapes may turn conical modes 'Mixed';
  mbseig names straight-line orbits 'mixed' (equal forward and backward components) and the
  conical modes backward / forward.
"""

from __future__ import annotations

import math
import sys
import warnings
from pathlib import Path

import numpy as np
from scipy.optimize import linear_sum_assignment

import mbseig
from mbseig.model.spatial_whirl import whirl

CASE = Path(__file__).resolve().parent.parent / "cases" / "rigid_rotor.toml"
SPEEDS = (0.0, 300.0, 600.0)


def closed_form(p, Omega):
    Kty, Ktz = 2 * p["kz"] * p["a"] ** 2, 2 * p["ky"] * p["a"] ** 2
    b = p["It"] * (Kty + Ktz) + p["Jp"] ** 2 * Omega ** 2
    r = math.sqrt(b * b - 4 * p["It"] ** 2 * Kty * Ktz)
    return sorted([math.sqrt(p["kx"] / p["m"]), math.sqrt(2 * p["ky"] / p["m"]),
                   math.sqrt(2 * p["kz"] / p["m"]), math.sqrt((b - r) / (2 * p["It"] ** 2)),
                   math.sqrt((b + r) / (2 * p["It"] ** 2))])


def ross_rotor(rs, p, E):
    mat = rs.Material(name="rigid", rho=1e-6, E=E, G_s=E / 2.6)
    shaft = [rs.ShaftElement(L=p["a"], idl=0.0, odl=0.05, material=mat, n=i) for i in range(2)]
    disk = rs.DiskElement(n=1, m=p["m"], Id=p["It"], Ip=p["Jp"])
    b1 = rs.BearingElement(n=0, kxx=p["ky"], kyy=p["kz"], cxx=0.0, kzz=p["kx"])
    b2 = rs.BearingElement(n=2, kxx=p["ky"], kyy=p["kz"], cxx=0.0)
    return rs.Rotor(shaft, [disk], [b1, b2])


def main():
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            import ross as rs
    except Exception as exc:  # noqa: BLE001 - ImportError, or plotly 6 rejecting ROSS 2.3.0
        print(f"ROSS is not available ({type(exc).__name__}: {str(exc).splitlines()[0][:80]}); "
              f"pip install ross-rotordynamics 'plotly<6' to run this benchmark")
        return 0
    warnings.simplefilter("ignore")
    for Omega in SPEEDS:
        a = mbseig.analyze(CASE, params={"Omega": Omega})
        p = a.model.parameters
        md = a.modes
        keep = [k for k in range(len(md)) if md.kind[k] != "rigid-body"]
        ours = md.omega_n[keep]
        ours_whirl = [whirl(a.model, a.eq.q, md.shapes[:, k], md.eigenvalues[k]) for k in keep]
        ref = np.array(closed_form(p, Omega))
        print(f"\nOmega = {Omega:g} rad/s: natural frequencies [rad/s] and whirl")
        print(f"  {'closed form':>14} {'mbseig':>14} {'rel':>8} {'whirl':>9}", end="")
        runs = [(1e17, False), (1e17, True), (1e15, True)]
        for E, sparse in runs:
            print(f" | ROSS E={E:.0e} {'sparse' if sparse else 'dense':<6} {'rel':>8} {'whirl':>9}", end="")
        print()
        cols = []
        for E, sparse in runs:
            modal = ross_rotor(rs, p, E).run_modal(speed=Omega, num_modes=14, sparse=sparse)
            wn = np.asarray(modal.wn)
            wh = [s.whirl for s in modal.shapes]
            _, pick = linear_sum_assignment(np.abs(wn[None, :] - ref[:, None]))  # one-to-one
            cols.append([(wn[j], wh[j]) for j in pick])
        for i, w in enumerate(ref):
            print(f"  {w:14.8f} {ours[i]:14.8f} {abs(ours[i] - w) / w:8.1e} {ours_whirl[i]:>9}", end="")
            for c in cols:
                print(f" | {c[i][0]:25.8f} {abs(c[i][0] - w) / w:8.1e} {c[i][1]:>9}", end="")
            print()
    return 0


if __name__ == "__main__":
    sys.exit(main())
