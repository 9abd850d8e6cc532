"""Rolling disk / hoop on a horizontal plane (no slip), derived with
sympy.physics.mechanics.KanesMethod.  Own formulation (not the sympy docs one):

  q1 = psi   heading (yaw, about N.z)
  q2 = phi   lean (about the heading axis Y.x)
  q3 = theta spin (about the axle L.y)
  q4, q5   = x, y of the ground contact point
  u_i = q_i'  (i = 1..5); u1, u2, u3 independent, u4, u5 dependent through the
  two nonholonomic constraints  v(material contact point of the disk) = 0.

Inertia about the centre: Id (any diameter), Ip (polar, about the axle).
Uniform thin disk: Id = m r^2/4, Ip = m r^2/2.  Thin hoop: Id = m r^2/2, Ip = m r^2.

build() returns the symbolic pieces used by rolling_disk.py.
"""
import sympy as sm
import sympy.physics.mechanics as me


def build():
    t = me.dynamicsymbols._t
    m, r, g, Id, Ip = sm.symbols('m r g I_d I_p', positive=True)
    q = me.dynamicsymbols('q1:6')
    u = me.dynamicsymbols('u1:6')
    q1, q2, q3, q4, q5 = q
    u1, u2, u3, u4, u5 = u

    N = me.ReferenceFrame('N')
    Y = N.orientnew('Y', 'Axis', [q1, N.z])
    L = Y.orientnew('L', 'Axis', [q2, Y.x])
    R = L.orientnew('R', 'Axis', [q3, L.y])

    origin = me.Point('O')
    origin.set_vel(N, 0)
    Cp = origin.locatenew('Cp', q4 * N.x + q5 * N.y)          # contact point (geometric)
    D = Cp.locatenew('D', r * L.z)                       # disk centre

    kd = [qi.diff(t) - ui for qi, ui in zip(q, u, strict=True)]
    kdd = {qi.diff(t): ui for qi, ui in zip(q, u, strict=True)}

    # angular velocity and centre velocity in terms of u
    R.set_ang_vel(N, R.ang_vel_in(N).subs(kdd))
    D.set_vel(N, D.pos_from(origin).dt(N).subs(kdd))
    # material point of the disk at the contact
    P = D.locatenew('P', -r * L.z)
    P.v2pt_theory(D, N, R)
    vP = P.vel(N)
    f_v = sm.Matrix([vP.dot(N.x), vP.dot(N.y)])
    f_v = f_v.applyfunc(sm.expand)
    assert sm.simplify(vP.dot(N.z)) == 0

    body = me.RigidBody('disk', D, R, m, (me.inertia(L, Id, Ip, Id), D))
    loads = [(D, -m * g * N.z)]

    KM = me.KanesMethod(N, q_ind=list(q), u_ind=[u1, u2, u3], kd_eqs=kd,
                        u_dependent=[u4, u5], velocity_constraints=f_v)
    fr, frstar = KM.kanes_equations([body], loads)
    return dict(KM=KM, q=list(q), u=list(u), f_v=f_v, syms=(m, r, g, Id, Ip),
                frames=(N, Y, L, R), points=(origin, Cp, D, P), t=t)
