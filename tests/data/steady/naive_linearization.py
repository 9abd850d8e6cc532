"""'Naive' linearization of the rolling disk about upright rolling at the
critical speed, and a second-formulation cross-check of the steady turn.

Model: the Peterson/Gede/Hubbard rolling-disc formulation exactly as in
sympy/physics/mechanics/tests/test_linearize.py::test_linearize_rolling_disc_kane
(q1 yaw, q2 lean, q3 spin, q4..q6 disc-centre coordinates with q6 dependent;
u1..u3 = disc angular velocity in the lean frame B, u4..u6 = centre velocity in
the disc frame C, dependent; N.z points DOWN, gravity m g A.z).  Linearized
with sympy's Linearizer (Peterson et al. 2015, Multibody Syst Dyn 33:143,
doi:10.1007/s11044-014-9436-5), whose state matrix is
    A = [[(A_qq + A_qu C_1) C_0,  A_qu C_2],
         [(A_uqc + A_uuc C_1) C_0, A_uuc C_2],
         [(A_uqd + A_uud C_1) C_0, A_uud C_2]]   (then M^-1, permutation)
with C_1 = -P_ud (f_v_u P_ud)^-1 f_v_q   (d f_v/dq: velocity constraints wrt positions)
and  A_uqc = -d f_a/dq                   (f_a = d/dt f_v: differentiated constraints wrt positions).
'Naive' variants zero one or both of these (internal attributes _C_1, _A_uqc
of sympy 1.14's Linearizer, set after _setup()).

Run: python3 naive_linearization.py
"""
import numpy as np
import sympy as sm
from sympy import symbols, Matrix, cos, sin, sqrt, solve, zeros
from sympy.physics.mechanics import (dynamicsymbols, ReferenceFrame, Point, dot, cross,
                                     inertia, KanesMethod, RigidBody)

t, r, m, g = symbols('t r m g')
q1, q2, q3, q4, q5, q6 = q = dynamicsymbols('q1:7')
q1d, q2d, q3d, q4d, q5d, q6d = qd = [qi.diff(t) for qi in q]
u1, u2, u3, u4, u5, u6 = u = dynamicsymbols('u1:7')
u1d, u2d, u3d, u4d, u5d, u6d = [ui.diff(t) for ui in u]
N = ReferenceFrame('N')
NO = Point('NO')
A = N.orientnew('A', 'Axis', [q1, N.z])
B = A.orientnew('B', 'Axis', [q2, A.x])
C = B.orientnew('C', 'Axis', [q3, B.y])
CO = NO.locatenew('CO', q4 * N.x + q5 * N.y + q6 * N.z)
w_c_n_qd = C.ang_vel_in(N)
w_b_n_qd = B.ang_vel_in(N)
C.set_ang_vel(N, u1 * B.x + u2 * B.y + u3 * B.z)
v_co_n_qd = CO.pos_from(NO).dt(N)
CO.set_vel(N, u4 * C.x + u5 * C.y + u6 * C.z)
P = CO.locatenew('P', r * B.z)
P.v2pt_theory(CO, N, C)
f_c = Matrix([q6 - dot(CO.pos_from(P), N.z)])
f_v = Matrix([dot(P.vel(N), uv) for uv in C])
kindiffs = Matrix([dot(w_c_n_qd - C.ang_vel_in(N), uv) for uv in B] +
                  [dot(v_co_n_qd - CO.vel(N), uv) for uv in N])
qdots = solve(kindiffs, qd)
B.set_ang_vel(N, w_b_n_qd.subs(qdots))
C.set_ang_acc(N, C.ang_vel_in(N).dt(B) + cross(B.ang_vel_in(N), C.ang_vel_in(N)))
Disc = RigidBody('Disc', CO, C, m, (inertia(C, m * r**2 / 4, m * r**2 / 2, m * r**2 / 4), CO))
KM = KanesMethod(N, [q1, q2, q3, q4, q5], [u1, u2, u3], kd_eqs=kindiffs,
                 q_dependent=[q6], configuration_constraints=f_c,
                 u_dependent=[u4, u5, u6], velocity_constraints=f_v)
KM.kanes_equations([Disc], [(CO, m * g * A.z)])

# general steady-motion operating point (from sympy's test): yaw rate q1d, lean q2, spin q3d
q_op = {q6: -r * cos(q2)}
u_op = {u1: 0, u2: sin(q2) * q1d + q3d, u3: cos(q2) * q1d,
        u4: -r * (sin(q2) * q1d + q3d) * cos(q3), u5: 0, u6: -r * (sin(q2) * q1d + q3d) * sin(q3)}
qd_op = {q2d: 0, q4d: -r * (sin(q2) * q1d + q3d) * cos(q1),
         q5d: -r * (sin(q2) * q1d + q3d) * sin(q1), q6d: 0}
ud_op = {u1d: 4 * g * sin(q2) / (5 * r) + sin(2 * q2) * q1d**2 / 2 + 6 * cos(q2) * q1d * q3d / 5,
         u2d: 0, u3d: 0,
         u4d: r * (sin(q2) * sin(q3) * q1d * q3d + sin(q3) * q3d**2),
         u5d: r * (4 * g * sin(q2) / (5 * r) + sin(2 * q2) * q1d**2 / 2
                   + 6 * cos(q2) * q1d * q3d / 5),
         u6d: -r * (sin(q2) * cos(q3) * q1d * q3d + cos(q3) * q3d**2)}


def state_matrix(variant):
    lin = KM.to_linearizer()
    lin._setup()
    if variant in ('drop_fv_q', 'drop_both'):
        lin._C_1 = zeros(*lin._C_1.shape)
    if variant in ('drop_fa_q', 'drop_both'):
        lin._A_uqc = zeros(*lin._A_uqc.shape)
    Am, _ = lin.linearize(op_point=[q_op, u_op, qd_op, ud_op], A_and_B=True)
    return Am


variants = ('correct', 'drop_fv_q', 'drop_fa_q', 'drop_both')
mats = {vname: state_matrix(vname) for vname in variants}
upright = {q1d: 0, q2: 0, m: 1, r: 1, g: 1}
print("== upright, m = r = g = 1, spin rate q3d (forward speed |q3d|*r); "
      "states [q1..q5, u1..u3] ==")
W = symbols('W')   # spin rate symbol; substitute q3d -> W BEFORE setting q3 = 0
for vname in variants:
    Au = sm.simplify(mats[vname].subs(q3d, W).subs(upright).subs({q1: 0, q3: 0}))
    print(f"\n[{vname}] u-rows at q1 = q3 = 0:")
    sm.pprint(Au[5:, :])
    ev = Au.subs(W, 1 / sqrt(3)).eigenvals()
    print(f"  exact eigenvalues at critical speed q3d = 1/sqrt(3): {ev}")
    for w in (0, sm.Rational(1, 2), 1 / sqrt(3), 1, 2):
        An = np.array(Au.subs(W, w).evalf(), dtype=float)
        e = np.linalg.eigvals(An)
        nz = sorted(e[np.abs(e) > 1e-7], key=lambda z: (z.real, z.imag))
        print(f"  q3d = {float(w):.6f}: nonzero eigenvalues "
              f"{[f'{z.real:.12f}{z.imag:+.12f}j' for z in nz]}")
    # invariance with respect to the (ignorable) angles q1, q3
    An2 = np.array(mats[vname].subs(q3d, W).subs(upright).subs({q1: 0.3, q3: 0.7})
                   .subs(W, 1 / np.sqrt(3)).evalf(), dtype=float)
    print(f"  at q1 = 0.3, q3 = 0.7 (critical speed): "
          f"{np.round(np.sort_complex(np.linalg.eigvals(An2)), 9)}")

# ---- steady turn cross-check (disk, m=r=g=1, lean into turn beta = 0.3, contact-path radius 5) --
print("\n== steady turn cross-check with this second formulation ==")
for beta, Rc in ((0.3, 5.0), (0.1, 5.0)):
    Ro = Rc - np.sin(beta)
    Om = np.sqrt(4 * np.tan(beta) / (6 * Ro + np.sin(beta)))
    # centre velocity -r*(sin q2 q1d + q3d) must be forward for q1d>0, lean q2=+beta
    w3 = -Om * Ro
    spin = w3 - np.sin(beta) * Om
    opn = {q1d: Om, q2: beta, m: 1, r: 1, g: 1}
    resid = float(ud_op[u1d].subs(q3d, spin).subs(opn))
    An = np.array(mats['correct'].subs(q3d, W).subs(opn).subs({q1: 0, q3: 0}).subs(W, spin).evalf(),
                  dtype=float)
    e = np.linalg.eigvals(An)
    nz = e[np.abs(e) > 1e-7]
    print(f"beta = {beta}, R_c = {Rc}: Omega = {Om:.15f}, steady-lean residual u1d = {resid:.1e}, "
          f"nonzero eigenvalues {[f'{z.real:+.14f}{z.imag:+.14f}j' for z in nz]}")
