"""Rolling disk / hoop: upright straight running and steady turning.

Model: rolling_disk_model.py (KanesMethod, own coordinates, u = q').
Linearization: dependent speeds u4, u5 (contact-point velocity) are eliminated
through the constraints *before* differentiating, so d(u_dep)/dq is included
(chain rule); the Jacobian of the full 8-state ODE (q1..q5, u1..u3) is taken
symbolically and evaluated at the operating point.
Cross-check of the steady-turn eigenvalues with a second, independent
formulation: sympy's own rolling-disc test model (Peterson/Gede/Hubbard
coordinates) linearized by sympy's Linearizer (see naive_linearization.py).

Run: python3 rolling_disk.py
"""
import numpy as np
import sympy as sm
from rolling_disk_model import build

S = build()
KM, q, u, f_v, t = S['KM'], S['q'], S['u'], S['f_v'], S['t']
m, r, g, Id, Ip = S['syms']
Q = sm.symbols('Q1:6')
U = sm.symbols('U1:6')
sub = dict(zip(q, Q, strict=True))
sub.update(dict(zip(u, U, strict=True)))
MM = sm.Matrix(KM.mass_matrix).xreplace(sub)     # 5x5: 3 Kane eqs + 2 differentiated constraints
FF = sm.Matrix(KM.forcing).xreplace(sub)
fv = f_v.xreplace(sub)
dep = sm.solve(list(fv), [U[3], U[4]], dict=True)[0]   # u4 = r u3 cos q1, u5 = r u3 sin q1
print("dependent speeds:", {k: sm.simplify(v) for k, v in dep.items()})

# reduced ODE x' = F(x), x = (q1..q5, u1..u3)
udot = MM.LUsolve(FF)[:3, :]
F = sm.Matrix([U[0], U[1], U[2], dep[U[3]], dep[U[4]], *udot]).xreplace(dep)
F = F.applyfunc(sm.simplify)
X = list(Q) + list(U[:3])
J = F.jacobian(X)

DISK = {Id: m * r**2 / 4, Ip: m * r**2 / 2}
HOOP = {Id: m * r**2 / 2, Ip: m * r**2}

# ------------------------------------------------------------------ upright
w, s, v = sm.symbols('omega s v')
op_up = {Q[0]: 0, Q[1]: 0, Q[2]: 0, Q[3]: 0, Q[4]: 0, U[0]: 0, U[1]: 0, U[2]: w}
Aup = sm.simplify(J.xreplace(op_up))
print("\n== upright straight running, spin rate u3 = omega (forward speed v = r*omega) ==")
print("lean/heading rows of A (x = [psi, phi, theta, x, y, psi', phi', theta']):")
sm.pprint(Aup[5:7, :])
cp = sm.factor((s * sm.eye(8) - Aup).det())
print("characteristic polynomial det(sI - A) =", cp)
k = (m * g * r - Ip * (Ip + m * r**2) * w**2 / Id) / (Id + m * r**2)
assert sm.simplify(cp - s**6 * (s**2 - k)) == 0
print("=> s^6 * (s^2 - k),  k = (m g r - Ip (Ip + m r^2) omega^2 / Id) / (Id + m r^2)")
for name, inert in (("uniform thin disk", DISK), ("thin hoop", HOOP)):
    kk = sm.simplify(k.subs(inert).subs(w, v / r))
    vcrit = sm.solve(sm.Eq(kk, 0), v)
    print(f"{name}: k = {sm.factor(kk)}, critical speed v^2 = "
          f"{sm.simplify(max(vcrit, key=lambda z: z.is_positive)**2)}")

print("\nuniform thin disk, m = r = g = 1: eigenvalues of the 4x4 lean/heading system "
      "(phi, psi, phi', psi')")
kd = sm.lambdify(v, sm.simplify(k.subs(DISK).subs(w, v / r).subs({m: 1, r: 1, g: 1})))
for vv in (0.0, 0.5, 1 / np.sqrt(3), 1.0, 2.0):
    kv = kd(vv)
    lam = np.sqrt(complex(kv))
    print(f"v = {vv:.15f}: k = {kv:+.15e}, "
          f"eigenvalues = 0, 0, +/-({lam.real:.15f}{lam.imag:+.15f}j)")
    # check against the numeric Jacobian of the full nonlinear model
    An = np.array(Aup.subs(DISK).subs({m: 1, r: 1, g: 1, w: vv}).evalf(), dtype=float)
    ev = np.linalg.eigvals(An)
    assert np.min(np.abs(ev - lam)) < 1e-5 and np.min(np.abs(ev + lam)) < 1e-5
print("thin hoop, m = r = g = 1: k = (1 - 4 v^2)/(3/2)")
kh = sm.lambdify(v, sm.simplify(k.subs(HOOP).subs(w, v / r).subs({m: 1, r: 1, g: 1})))
for vv in (0.0, 0.5, 1.0):
    lam = np.sqrt(complex(kh(vv)))
    print(f"  v = {vv}: eigenvalues 0, 0, +/-({lam.real:.15f}{lam.imag:+.15f}j)")

# ------------------------------------------------------------------ steady turn
print("\n== steady turning ==")
phi, Om, th = sm.symbols('phi Omega thetadot')
op_st = {Q[0]: 0, Q[1]: phi, Q[2]: 0, Q[3]: 0, Q[4]: 0, U[0]: Om, U[1]: 0, U[2]: th}
lean_acc = sm.simplify(F[6].xreplace(op_st))          # phi'' at the candidate steady motion
print("phi'' at (phi, psi' = Omega, phi' = 0, theta' = thetadot):", sm.factor(lean_acc))
beta, Ro, Rc = sm.symbols('beta R_o R_c', positive=True)
# lean INTO a left turn (Omega > 0): phi = -beta; centre speed r*omega3
# with omega3 = thetadot + Omega sin(phi)
# contact-point path radius R_c = r thetadot/Omega, centre path radius R_o = R_c - r sin(beta)
cond = sm.simplify(lean_acc.subs({phi: -beta, th: Rc * Om / r}))
Wsym = sm.Symbol('W', positive=True)   # W = Omega^2
Om2_expr = sm.simplify(sm.solve(sm.numer(sm.together(cond)).subs(Om, sm.sqrt(Wsym)), Wsym)[0])
print("general: Omega^2 =", sm.simplify(Om2_expr), "   (R_c = contact-point path radius)")
Om2_Ro = sm.simplify(Om2_expr.subs(Rc, Ro + r * sm.sin(beta)))
print("general: Omega^2 =", Om2_Ro, "   (R_o = centre path radius)")
for name, inert in (("disk", DISK), ("hoop", HOOP)):
    print(f"  {name}: Omega^2 = {sm.simplify(Om2_expr.subs(inert))}  "
          f"= {sm.simplify(Om2_Ro.subs(inert))}")

def steady_turn_case(beta_v, Rc_v, inert=DISK, label="disk"):
    vals = {m: 1, r: 1, g: 1}
    W = float(Om2_expr.subs(inert).subs(vals).subs({beta: beta_v, Rc: Rc_v}))
    Omv = np.sqrt(W)
    thv = Rc_v * Omv / 1.0
    op = {Q[0]: 0, Q[1]: -beta_v, Q[2]: 0, Q[3]: 0, Q[4]: 0, U[0]: Omv, U[1]: 0, U[2]: thv}
    resid = float(F[6].subs(inert).subs(vals).xreplace(op))
    An = np.array(J.subs(inert).subs(vals).xreplace(op).evalf(30), dtype=float)
    ev = np.linalg.eigvals(An)
    nz = ev[np.abs(ev) > 1e-6]
    print(f"\n{label}, m=r=g=1, lean into turn beta = {beta_v} rad, "
          f"contact-path radius R_c = {Rc_v}:")
    print(f"  Omega (yaw rate)          = {Omv:.15f} rad/s   (lean-equation residual {resid:.1e})")
    print(f"  contact-point speed v_c   = R_c*Omega = {Rc_v * Omv:.15f}")
    print(f"  centre path radius R_o    = {Rc_v - np.sin(beta_v):.15f}, "
          f"centre speed = {(Rc_v - np.sin(beta_v)) * Omv:.15f}")
    print(f"  spin rate relative to lean frame theta' = {thv:.15f}, "
          f"total axle spin omega3 = {thv - Omv * np.sin(beta_v):.15f}")
    print("  eigenvalues (8 states):",
          ", ".join(f"{z.real:+.12f}{z.imag:+.12f}j"
                    for z in sorted(ev, key=lambda z: (abs(z), z.imag))))
    print("  nonzero pair:", ", ".join(f"{z.real:+.14f}{z.imag:+.14f}j" for z in nz))
    return Omv, thv, ev

def naive_in_this_formulation():
    """Same 'naive' manipulations as naive_linearization.py, but in THIS formulation
    (u = q', contact-point coordinates).  (a) drop d(u_dep)/dq, i.e. d f_v/dq;
    (b) drop the whole (d f_v/dq) q' term of the differentiated constraints
    (rows 4-5 of the forcing: r u1 u3 sin q1, -r u1 u3 cos q1)."""
    vals = {m: 1, r: 1, g: 1}
    wc = 1 / np.sqrt(3)
    op = {Q[0]: 0, Q[1]: 0, Q[2]: 0, Q[3]: 0, Q[4]: 0, U[0]: 0, U[1]: 0, U[2]: wc}
    opd = dict(op)
    opd.update({U[3]: wc, U[4]: 0})
    udot_keep = MM.LUsolve(FF)[:3, :]                      # contains U4, U5 symbols (if any)
    Fk = sm.Matrix([U[0], U[1], U[2], U[3], U[4], *udot_keep])
    Bu = sm.Matrix([[dep[U[3]].diff(x) for x in U[:3]], [dep[U[4]].diff(x) for x in U[:3]]])
    Ja = Fk.jacobian(Q).row_join(Fk.jacobian(U[:3]) + Fk.jacobian(U[3:]) * Bu)   # no d(u_dep)/dq
    FF2 = FF.copy()
    FF2[3] = 0
    FF2[4] = 0
    F2 = sm.Matrix([U[0], U[1], U[2], dep[U[3]], dep[U[4]], *MM.LUsolve(FF2)[:3, :]]).xreplace(dep)
    Jb = F2.jacobian(X)
    for lab, Jx in (("(a) drop d f_v/dq", Ja), ("(b) drop (d f_v/dq) q' in f_a", Jb)):
        An = np.array(Jx.subs(DISK).subs(vals).xreplace(opd).evalf(), dtype=float)
        print(f"  {lab}: eigenvalues at v = 1/sqrt(3):",
              np.round(np.sort_complex(np.linalg.eigvals(An)), 6))


if __name__ == "__main__":
    for b in (0.3, 0.1):
        steady_turn_case(b, 5.0)
    steady_turn_case(0.3, 5.0, HOOP, "hoop")
    print("\n== 'naive' variants in this formulation (disk, m=r=g=1, upright, critical speed) ==")
    naive_in_this_formulation()
