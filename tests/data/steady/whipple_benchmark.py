"""Whipple bicycle benchmark (Meijaard, Papadopoulos, Ruina, Schwab 2007,
Proc. R. Soc. A 463:1955-1982, doi:10.1098/rspa.2007.1857).

1. Recompute M, C1, K0, K2 from the Table 1 parameters with the Appendix A
   formulas (independent of the printed matrices), in mpmath at 40 digits.
2. Build A(v) = [[0, I], [-M^-1 (g K0 + v^2 K2), -M^-1 v C1]] from the
   *printed* matrices (eq. 5.4 / Appendix) and compare its eigenvalues at
   v = 0..10 with Table 2 (transcribed values below).
3. Root-find the weave speed v_w (Hurwitz determinant = 0, brentq) and the
   capsize speed v_c (det(g K0 + v^2 K2) = 0), plus the weave/real
   bifurcation speed v_d (double real root), both in float64 (brentq) and
   in mpmath (findroot, 40 digits).
Run: python3 whipple_benchmark.py
"""
import numpy as np
import mpmath as mp
from scipy.optimize import brentq

mp.mp.dps = 40

# ---- Table 1 (benchmark parameters) ----
P = dict(w=mp.mpf('1.02'), c=mp.mpf('0.08'), lam=mp.pi / 10, g=mp.mpf('9.81'),
         rR=mp.mpf('0.3'), mR=mp.mpf('2'), IRxx=mp.mpf('0.0603'), IRyy=mp.mpf('0.12'),
         xB=mp.mpf('0.3'), zB=mp.mpf('-0.9'), mB=mp.mpf('85'),
         IBxx=mp.mpf('9.2'), IByy=mp.mpf('11'), IBzz=mp.mpf('2.8'), IBxz=mp.mpf('2.4'),
         xH=mp.mpf('0.9'), zH=mp.mpf('-0.7'), mH=mp.mpf('4'),
         IHxx=mp.mpf('0.05892'), IHyy=mp.mpf('0.06'), IHzz=mp.mpf('0.00708'),
         IHxz=mp.mpf('-0.00756'),
         rF=mp.mpf('0.35'), mF=mp.mpf('3'), IFxx=mp.mpf('0.1405'), IFyy=mp.mpf('0.28'))


def canonical(p):
    """Appendix A of Meijaard et al. 2007 -> (M, C1, K0, K2) as mpmath matrices."""
    w, c, lam = p['w'], p['c'], p['lam']
    mR, mB, mH, mF = p['mR'], p['mB'], p['mH'], p['mF']
    rR, rF = p['rR'], p['rF']
    xB, zB, xH, zH = p['xB'], p['zB'], p['xH'], p['zH']
    IRxx, IRyy, IFxx, IFyy = p['IRxx'], p['IRyy'], p['IFxx'], p['IFyy']
    IRzz, IFzz = IRxx, IFxx                      # axisymmetric wheels
    mT = mR + mB + mH + mF
    xT = (xB * mB + xH * mH + w * mF) / mT
    zT = (-rR * mR + zB * mB + zH * mH - rF * mF) / mT
    ITxx = IRxx + p['IBxx'] + p['IHxx'] + IFxx + mR * rR**2 + mB * zB**2 + mH * zH**2 + mF * rF**2
    ITxz = p['IBxz'] + p['IHxz'] - mB * xB * zB - mH * xH * zH + mF * w * rF
    ITzz = IRzz + p['IBzz'] + p['IHzz'] + IFzz + mB * xB**2 + mH * xH**2 + mF * w**2
    mA = mH + mF
    xA = (xH * mH + w * mF) / mA
    zA = (zH * mH - rF * mF) / mA
    IAxx = p['IHxx'] + IFxx + mH * (zH - zA)**2 + mF * (rF + zA)**2
    IAxz = p['IHxz'] - mH * (xH - xA) * (zH - zA) + mF * (w - xA) * (rF + zA)
    IAzz = p['IHzz'] + IFzz + mH * (xH - xA)**2 + mF * (w - xA)**2
    uA = (xA - w - c) * mp.cos(lam) - zA * mp.sin(lam)
    IAll = (mA * uA**2 + IAxx * mp.sin(lam)**2 + 2 * IAxz * mp.sin(lam) * mp.cos(lam)
            + IAzz * mp.cos(lam)**2)
    IAlx = -mA * uA * zA + IAxx * mp.sin(lam) + IAxz * mp.cos(lam)
    IAlz = mA * uA * xA + IAxz * mp.sin(lam) + IAzz * mp.cos(lam)
    mu = c / w * mp.cos(lam)
    SR, SF = IRyy / rR, IFyy / rF
    ST = SR + SF
    SA = mA * uA + mu * mT * xT
    M = mp.matrix([[ITxx, IAlx + mu * ITxz],
                   [IAlx + mu * ITxz, IAll + 2 * mu * IAlz + mu**2 * ITzz]])
    K0 = mp.matrix([[mT * zT, -SA], [-SA, -SA * mp.sin(lam)]])
    K2 = mp.matrix([[0, (ST - mT * zT) / w * mp.cos(lam)],
                    [0, (SA + SF * mp.sin(lam)) / w * mp.cos(lam)]])
    C1 = mp.matrix([[0, mu * ST + SF * mp.cos(lam) + ITxz / w * mp.cos(lam) - mu * mT * zT],
                    [-(mu * ST + SF * mp.cos(lam)),
                     IAlz / w * mp.cos(lam) + mu * (SA + ITzz / w * mp.cos(lam))]])
    return M, C1, K0, K2


# ---- printed matrices (paper eq. 5.4; transcribed identically in
# moorepants/DynamicistToolKit dtk/bicycle.py::benchmark_matrices) ----
M_p = np.array([[80.81722, 2.31941332208709], [2.31941332208709, 0.29784188199686]])
C1_p = np.array([[0., 33.86641391492494], [-0.85035641456978, 1.68540397397560]])
K0_p = np.array([[-80.95, -2.59951685249872], [-2.59951685249872, -0.80329488458618]])
K2_p = np.array([[0., 76.59734589573222], [0., 2.65431523794604]])
G = 9.81

# ---- Table 2 (transcription: hazelnusse/OBD whipple/tests/whipple-eigs-unittest.cpp
# @b9e7a27f; castering value at v=5 also in moorepants/dissertation
# src/eom/linear_comparison.py; at v=4 the 16-digit value -12.15861426576447 is
# from a third-party test transcription (OBD has -12.15861426576450); see README) ----
TABLE2 = {
    0: [5.53094371765393, 3.13164324790656, -3.13164324790656, -5.53094371765393],
    1: [3.52696170990070 + 0.80774027519930j, 3.52696170990070 - 0.80774027519930j,
        -3.13423125066578, -7.11008014637442],
    2: [2.68234517512745 + 1.68066296590675j, 2.68234517512745 - 1.68066296590675j,
        -3.07158645641514, -8.67387984831735],
    # 3: only 15 sig. digits in the transcriptions found
    3: [1.70675605663975 + 2.31582447384325j, 1.70675605663975 - 2.31582447384325j,
        -2.63366137253667, -10.3510146724592],
    4: [0.41325331521125 + 3.07910818603206j, 0.41325331521125 - 3.07910818603206j,
        -1.42944427361326, -12.15861426576447],
    5: [-0.77534188219585 + 4.46486771378823j, -0.77534188219585 - 4.46486771378823j,
        -0.32286642900409, -14.07838969279822],
    # 6: only 15 sig. digits in the transcriptions found
    6: [-1.52644486584142 + 5.87673060598709j, -1.52644486584142 - 5.87673060598709j,
        -0.00406690076970, -16.0853712309803],
    7: [-2.13875644258362 + 7.19525913329805j, -2.13875644258362 - 7.19525913329805j,
        0.10268170574766, -18.15788466125262],
    8: [-2.69348683581097 + 8.46037971396931j, -2.69348683581097 - 8.46037971396931j,
        0.14327879765713, -20.27940894394569],
    9: [-3.21675402252485 + 9.69377351531791j, -3.21675402252485 - 9.69377351531791j,
        0.15790184030917, -22.43788559040858],
    10: [-3.72016840437287 + 10.90681139476287j, -3.72016840437287 - 10.90681139476287j,
         0.16105338653172, -24.62459635017404],
}


def state_matrix(v, M=M_p, C1=C1_p, K0=K0_p, K2=K2_p, g=G):
    Minv = np.linalg.inv(M)
    return np.block([[np.zeros((2, 2)), np.eye(2)],
                     [-Minv @ (g * K0 + v**2 * K2), -Minv @ (v * C1)]])


def char_coeffs(v, M, C1, K0, K2, g):
    """det(M s^2 + v C1 s + g K0 + v^2 K2) = a4 s^4 + ... + a0 (works for float or mpf)."""
    K = [[g * K0[i, j] + v**2 * K2[i, j] for j in range(2)] for i in range(2)]
    C = [[v * C1[i, j] for j in range(2)] for i in range(2)]
    Mm = [[M[i, j] for j in range(2)] for i in range(2)]
    def d(X, Y):  # mixed 2x2 "determinant" terms
        return X[0][0] * Y[1][1] + Y[0][0] * X[1][1] - X[0][1] * Y[1][0] - Y[0][1] * X[1][0]
    a4 = Mm[0][0] * Mm[1][1] - Mm[0][1] * Mm[1][0]
    a3 = d(Mm, C)
    a2 = d(Mm, K) + C[0][0] * C[1][1] - C[0][1] * C[1][0]
    a1 = d(C, K)
    a0 = K[0][0] * K[1][1] - K[0][1] * K[1][0]
    return a4, a3, a2, a1, a0


def hurwitz3(v, *mats):
    a4, a3, a2, a1, a0 = char_coeffs(v, *mats)
    return a3 * a2 * a1 - a4 * a1**2 - a3**2 * a0   # = 0 <=> a pair s = +/- i w


def capsize_f(v, *mats):
    return char_coeffs(v, *mats)[4]


def main():
    np.set_printoptions(precision=17)
    Mc, C1c, K0c, K2c = canonical(P)
    print("== M, C1, K0, K2 recomputed from Table 1 (Appendix A), 17 sig. digits ==")
    for name, X, Xp in (("M", Mc, M_p), ("C1", C1c, C1_p), ("K0", K0c, K0_p), ("K2", K2c, K2_p)):
        for i in range(2):
            for j in range(2):
                print(f"{name}[{i}{j}] = {mp.nstr(X[i, j], 17):>22}   "
                      f"printed {float(Xp[i, j])!r:>20}   diff {float(X[i, j]) - Xp[i, j]:+.1e}")

    print("\n== eigenvalues of A(v) from printed matrices vs Table 2 ==")
    worst = 0.0
    for v in range(11):
        ev = np.linalg.eigvals(state_matrix(float(v)))
        ref = np.array(TABLE2[v], dtype=complex)
        # match each reference value to the nearest computed eigenvalue
        errs = [np.min(np.abs(ev - r)) for r in ref]
        worst = max(worst, max(errs))
        evs = sorted(ev, key=lambda z: (-z.real, -z.imag))
        print(f"v={v:2d}: " + ", ".join(f"{z.real:.14f}{z.imag:+.14f}j" for z in evs)
              + f"   max|diff to Table 2| = {max(errs):.1e}")
    print(f"worst |numpy - Table 2| over v=0..10: {worst:.2e}")

    print("\n== eigenvalues from Table 1 parameters in mpmath (40 digits), 15 decimals, "
          "vs Table 2 ==")
    worst = 0
    for v in range(11):
        rts = mp.polyroots(char_coeffs(mp.mpf(v), Mc, C1c, K0c, K2c, P['g']),
                           maxsteps=500, extraprec=300)
        rts = sorted(rts, key=lambda z: (-mp.re(z), -mp.im(z)))
        ref = np.array(TABLE2[v], dtype=complex)
        errs = [min(abs(complex(z) - r) for z in rts) for r in ref]
        worst = max(worst, max(errs))
        print(f"v={v:2d}: "
              + ", ".join(f"{mp.nstr(mp.re(z), 17, min_fixed=-1, max_fixed=3)}"
                          f"{'+' if mp.im(z) >= 0 else '-'}{mp.nstr(abs(mp.im(z)), 17)}j"
                          for z in rts)
              + f"   max|diff to Table 2| = {max(errs):.1e}")
    print(f"worst |mpmath(Table 1) - Table 2| over v=0..10: {worst:.2e}")

    mats_f = (M_p, C1_p, K0_p, K2_p, G)
    vw = brentq(hurwitz3, 3.0, 5.0, args=mats_f, xtol=1e-15, rtol=4 * np.finfo(float).eps)
    vc = brentq(capsize_f, 5.0, 7.0, args=mats_f, xtol=1e-15, rtol=4 * np.finfo(float).eps)
    print("\n== critical speeds, float64 brentq on printed matrices ==")
    print(f"v_w (weave)   = {vw:.15f}   "
          f"eig imag at v_w: {np.abs(np.linalg.eigvals(state_matrix(vw)).imag).max():.14f}")
    print(f"v_c (capsize) = {vc:.15f}")

    # mpmath, printed matrices taken as exact decimals
    def to_mp(A):
        return mp.matrix([[mp.mpf(repr(float(A[i, j]))) for j in range(2)] for i in range(2)])

    mats_p = (to_mp(M_p), to_mp(C1_p), to_mp(K0_p), to_mp(K2_p), mp.mpf('9.81'))
    mats_c = (Mc, C1c, K0c, K2c, P['g'])
    for label, mats in (("printed matrices", mats_p),
                        ("Table 1 parameters (exact, lambda=pi/10)", mats_c)):
        vw_m = mp.findroot(lambda v, mats=mats: hurwitz3(v, *mats), mp.mpf(vw))
        vc_m = mp.findroot(lambda v, mats=mats: capsize_f(v, *mats), mp.mpf(vc))
        # weave frequency at v_w: s^2 = -a1/a3
        a4, a3, a2, a1, a0 = char_coeffs(vw_m, *mats)
        om = mp.sqrt(a1 / a3)
        # bifurcation speed v_d: where the weave pair of real roots coalesces
        # (double root => discriminant of the quartic = 0); find via resultant
        def disc(v, mats=mats):
            c = char_coeffs(v, *mats)
            p = [c[0], c[1], c[2], c[3], c[4]]
            dp = [4 * c[0], 3 * c[1], 2 * c[2], c[3]]
            # Sylvester resultant res(p, p')
            n, m_ = 4, 3
            S = mp.zeros(n + m_, n + m_)
            for i in range(m_):
                for j in range(n + 1):
                    S[i, i + j] = p[j]
            for i in range(n):
                for j in range(m_ + 1):
                    S[m_ + i, i + j] = dp[j]
            return mp.det(S)
        vd_m = mp.findroot(disc, mp.mpf('0.684'))
        cd = char_coeffs(vd_m, *mats)
        # the double root is a root of p'(s) = 4 a4 s^3 + 3 a3 s^2 + 2 a2 s + a1
        sd = mp.findroot(lambda s, cd=cd: (4 * cd[0] * s**3 + 3 * cd[1] * s**2 + 2 * cd[2] * s
                                           + cd[3]),
                         mp.mpf('3.78'))
        print(f"\n== mpmath (40 digits), {label} ==")
        print(f"v_d (weave real-pair bifurcation) = {mp.nstr(vd_m, 20)}, "
              f"double root = {mp.nstr(sd, 20)}")
        print(f"v_w = {mp.nstr(vw_m, 20)}, weave frequency at v_w = {mp.nstr(om, 20)} rad/s")
        print(f"v_c = {mp.nstr(vc_m, 20)}")


if __name__ == "__main__":
    main()
