"""Equilibrium branches along a parameter: pseudo-arclength continuation with folds and branch
points (docs/design.md, "Equilibrium").

A family p ↦ model(p) (built by the studies from a case, :mod:`mbseig.studies.continuation`)
defines

    R(y, p) = [g(q) − Φ_Sᵀ λ; −Φ_S(q)] = 0,     y = (q, λ),

on an independent subset S of the constraint rows (redundant rows carry no information on the
branch; the multipliers of all rows are recomputed by least squares at each reported point).
J = −∂R/∂y is the Newton matrix of :mod:`~mbseig.statics.newton`, R_p = ∂R/∂p a forward
difference with step ``FD_REL``·p_scale (p_scale: the span of the sweep).

Tangent: J ẏ = R_p ṗ, normalized so that ‖ẏ_q‖²_W + (ṗ/p_scale)² = 1 in the model's scales
(W = diag 1/ℓ², multipliers weightless), oriented along the previous tangent.  At a grid point
reached directly from the previous one, R_p is the difference to the previous point's model
(:meth:`Family.Rp_back`, no model built at p + h: in a sweep whose parameter enters inverse
statics, a build costs a resolve of the commands); it serves the predictor and the sense of p.
When the sense of p or the sign of det J differs from the previous point's (a fold or branch
point between them), or det J has no sign, both tangents are recomputed with the forward
difference and the events are decided on those (``record["tangents_by_difference"]`` counts
the points that kept the difference tangent).

Step: while the branch moves towards the next grid value p_g, the equilibrium at p_g from the
tangent predictor bent through the previous point (second order, :func:`_predict`): plain Newton
while its corrections shrink, then the statics' own Newton (natural-parameter continuation: the
grid point itself), accepted when it converges within ``REACH`` × the predicted step of its
predictor (so it cannot land on another branch) and the tangent keeps its sense of p (no fold
between); otherwise a pseudo-arclength step
(Keller): predictor z + ds·t, corrector Newton on [R(y, p) = 0; (Wt)ᵀ(z − z_pred) = 0] with the
bordered matrix B = [[J, −R_p], [(Wt)ᵀ]] (:func:`~mbseig.statics.linalg.solve_bordered`),
to ``STEP_TOL``.  An arclength step whose corrector does not converge in ``CORRECTOR_ITER``
iterations is halved; an easy one (≤ ``EASY`` iterations) lengthens the next
by 3/2, up to ds_max.  Grid values an arclength step passes are corrected at their value.

Folds (limit points): ṗ changes sign between two points; located by Brent's method on ṗ(s)
along the arclength (each evaluation a corrector on the hyperplane at distance s), so p at the
fold, an extremum of p(s), is accurate to O(xtol_s²).  Branch points: the sign of det B
changes (it does not at a fold); located by bisection on that sign.  There the null space of
[J, −R_p] is two-dimensional; its vector orthogonal to the tangent is the direction of the
other branch, and the follower switches to it when the branch it is on has lost static stability
there and the other is statically stable.  After a fold the branch turns back; it is followed
until it turns forward again (an S-curve), leaves the swept range or has run ``BACK_ARC`` of
the normalized arclength, and the next grid value is then reached by a fresh static solve from
the fold (the jump of a snap-through), which starts a new segment.
"""

from __future__ import annotations

import numpy as np

from ..errors import EquilibriumError, MbseigError
from ..numerics import LazyModule
from .branch import (
    Branch,
    BranchPoint,
    branch_point_at,
    correct_arclength,
    correct_fixed,
    locate_branch_point,
    locate_fold,
    second_direction,
    tangent,
)
from .family import CORRECTOR_ITER, CTOL, FD_REL, Family

spla = LazyModule("scipy.sparse.linalg")  # sparse solvers: imported at first use

__all__ = ["Family", "BranchPoint", "Branch", "follow", "CORRECTOR_ITER", "FD_REL", "CTOL"]

STEP_TOL = 1e-8  # an arclength step between grid points is corrected to this (model scales)
EASY = 3  # a corrector converged in at most EASY iterations lengthens the next step
DS_MIN = 1e-9  # smallest step (normalized arclength) before a segment is given up
DS_MAX = 0.1  # largest step (normalized arclength: at least ten steps over the swept range)
REACH = 0.25  # a grid point's corrector may end this far from its predictor (× the step)
BACK_ARC = 0.3  # arclength followed along a branch that turned back, before jumping forward


# ---------------------------------------------------------------------------------------------
def follow(fam, values, y0, *, stability=None, restart=None, switch=True, ds_max=None,
           max_steps=None, xtol=1e-10):
    """Follow the branch through (values[0], y0) across the grid ``values`` (module docstring).

    stability(model, q, λ) → "stable" | "unstable" | ...: the static stability used to decide a
        branch switch (None: never switch).
    restart(p, q_start) → q: a static solve at p from q_start (the jump after a fold).
    Returns a :class:`Branch`: ``grid[k]`` the point at values[k] (None where not reached),
    ``events`` the folds, branch points, switches and jumps with their parameter values.
    """
    return _Follower(fam, values, y0, stability=stability, restart=restart, switch=switch,
                     ds_max=ds_max, max_steps=max_steps, xtol=xtol).run()


class _Follower:
    """The state of one continuation across a grid: the current point z = (y, p) with its
    tangent t, the step ds, the next grid index, the segment, and the counts for the record.

    One step (:meth:`run`): a trial point (the next grid value from the tangent predictor, else
    a pseudo-arclength step), its tangent, then the events between the two points (a fold:
    ṗ changes sign; a branch point: det B changes sign, with a switch to the stable branch),
    the grid values passed, and the next step length.  A step that fails halves ds; a segment
    that cannot go on jumps to the next grid value by a fresh static solve."""

    def __init__(self, fam, values, y0, *, stability, restart, switch, ds_max, max_steps, xtol):
        self.fam, self.stability, self.restart, self.switch, self.xtol = (
            fam, stability, restart, switch, xtol)
        values = self.values = np.asarray(values, dtype=float)
        self.dirn = 1.0 if values[-1] >= values[0] else -1.0
        spacing = float(np.min(np.abs(np.diff(values)))) / fam.p_scale if values.size > 1 else 1.0
        self.ds_max = min(2.0 * spacing, DS_MAX) if ds_max is None else ds_max
        self.spacing = min(spacing, self.ds_max)
        self.max_steps = 40 * values.size if max_steps is None else max_steps
        self.br = Branch(grid=[None] * values.size)
        self.segment = 0
        t = tangent(fam, y0, values[0], direction=self.dirn)
        if t is None:
            raise EquilibriumError("no tangent at the first point of the sweep",
                                   element="continuation")
        z = np.concatenate([y0, [values[0]]])
        cur = branch_point_at(fam, z, t, "start", self.segment)
        cur.grid_index = 0
        self.br.points.append(cur)
        self.br.grid[0] = cur
        self.z, self.t, self.cur = z, t, cur
        self.k_next, self.ds, self.steps, self.back = 1, self.spacing, 0, 0
        self.accepted = self.rejected = self.approx = 0
        self.land, self.t_exact = True, True
        self.fold_z = None  # the last fold: where a jump past it starts from
        self.last_B = cur.det_B
        self.z_prev, self.t_prev, self.ds_prev = z, t, 0.0
        self.pending_jump = False

    def run(self) -> Branch:
        values = self.values
        while self.k_next < values.size and self.steps < self.max_steps:
            if self.pending_jump:
                self.pending_jump = False
                if not self._jump():
                    break
                continue
            self.steps += 1
            new = self._trial()
            if new is None:
                self.rejected += 1
                self.ds *= 0.5
                self.pending_jump = self.ds < DS_MIN * max(self.spacing, 1.0)
                continue
            new_z, its, ds_used, landed = new
            step = self._tangent(new_z, its, landed)
            if step is None:
                self.rejected += 1
                self.ds *= 0.5
                continue
            t_new, newp = step
            t = self.t
            if landed and t[-1] * t_new[-1] < 0:  # the landing passed a fold: step along the arc
                self.land, self.ds = False, abs(ds_used)
                continue
            t_exact_new = newp is None
            self.land = True
            self.accepted += 1
            fold = t[-1] * t_new[-1] < 0  # folds: ṗ changes sign
            if fold:
                self._fold(new_z, t_new, ds_used)
            if newp is None:
                newp = branch_point_at(self.fam, new_z, t_new, "grid" if landed else "step",
                                       self.segment, its)
            if self._branch_point(newp, ds_used, fold):
                continue
            if landed:
                newp.grid_index = self.k_next
                self.br.grid[self.k_next] = newp
                self.fam.pin(newp.p, newp.y)
                self.k_next += 1
            else:
                self._pass_grid_values(new_z, t_new)
            self._advance(new_z, t_new, newp, ds_used, t_exact_new, its)
        return self._finish()

    def _trial(self):
        """(z, corrector iterations, step, landed on the grid value) of the next point, or None."""
        fam, z, t = self.fam, self.z, self.t
        p_g = self.values[self.k_next]
        forward = t[-1] * self.dirn > 0
        if self.land and forward:  # the next grid value directly, from the tangent predictor
            ds_g = (p_g - z[-1]) / t[-1]
            res = correct_fixed(fam, _predict(z, t, self.z_prev, p_g), p_g,
                                REACH * abs(ds_g) + 1e-9)
            if res is not None:
                return np.concatenate([res[0], [p_g]]), res[1], ds_g, True
        res = correct_arclength(fam, z, t, self.ds, STEP_TOL)
        if res is not None:
            return res[0], res[1], self.ds, False
        return None

    def _tangent(self, new_z, its, landed):
        """(t, point or None) at the trial point, or None: by the difference ∂R/∂p from the
        previous model where no sign changed, else exact (and the start's tangent made exact)."""
        fam, z, t, cur = self.fam, self.z, self.t, self.cur
        t_new = newp = None
        if landed and new_z[-1] != z[-1]:  # ∂R/∂p from the previous point's model (no build)
            t_new = tangent(fam, new_z[:-1], new_z[-1], prev=t,
                            rp=fam.Rp_back(new_z[:-1], new_z[-1], z[-1]))
            if t_new is not None:
                newp = branch_point_at(fam, new_z, t_new, "grid", self.segment, its)
                if not (newp.det_J and newp.det_J == cur.det_J and t[-1] * t_new[-1] > 0):
                    t_new = None  # a sign changed: decided on the exact tangents below
                else:
                    self.approx += 1
        if t_new is None:
            if not self.t_exact:  # the exact tangent at the start of the step
                t_z = tangent(fam, z[:-1], z[-1], prev=t)
                if t_z is not None:
                    t = self.t = cur.tangent = t_z
                    if cur.det_J and abs(t[-1]) > 1e-12:  # its det B from the exact ṗ
                        cur.det_B = self.last_B = cur.det_J * int(np.sign(t[-1]))
                self.t_exact = True
            t_new = tangent(fam, new_z[:-1], new_z[-1], prev=t)
            newp = None
            if t_new is None:
                return None
        return t_new, newp

    def _fold(self, new_z, t_new, ds_used):
        """Locate the fold between z and the new point and record it."""
        fam, z, t, br = self.fam, self.z, self.t, self.br
        try:
            zf, tf = locate_fold(fam, z, t, ds_used, self.xtol)
            self.fold_z = zf
            fp = branch_point_at(fam, zf, tf, "fold", self.segment)
            br.points.append(fp)
            br.events.append({"type": "fold", "p": fp.p, "segment": self.segment,
                              "turns": "back" if t_new[-1] * self.dirn < 0 else "forward",
                              "point": len(br.points) - 1})
        except MbseigError:
            br.events.append({"type": "fold", "p": float(0.5 * (z[-1] + new_z[-1])),
                              "segment": self.segment, "located": False})

    def _branch_point(self, newp, ds_used, fold) -> bool:
        """Branch points: det B changes sign (B singular on a point itself: judged at the
        next).  Not at a fold: where Φ_q loses rank (a kinematic fold, a dead point) det J has
        a double zero and det B changes sign there instead.  True when the follower switched
        to the other branch (the step is then done)."""
        fam, br = self.fam, self.br
        if not (newp.det_B and self.last_B and newp.det_B != self.last_B and not fold):
            return False
        z_from, t_from, ds_from = ((self.z, self.t, ds_used) if self.cur.det_B else
                                   (self.z_prev, self.t_prev, self.ds_prev + ds_used))
        found = locate_branch_point(fam, z_from, t_from, ds_from, self.last_B)
        if found is None:
            return False
        bp = branch_point_at(fam, found[0], found[1], "branch point", self.segment)
        br.points.append(bp)
        ev = {"type": "branch point", "p": bp.p, "segment": self.segment,
              "point": len(br.points) - 1}
        br.events.append(ev)
        if not (self.switch and self.stability is not None):
            return False
        sw = _switch(fam, bp, newp, ds_used, self.stability, self.segment + 1, self.dirn)
        if sw is None:
            return False
        ev["switched"] = True
        (self.z, self.t, self.cur), self.segment = sw, self.segment + 1
        self.t_exact = True
        br.points.append(self.cur)
        self._fresh()
        return True

    def _pass_grid_values(self, new_z, t_new):
        """Grid values the arc passed going forward: each by a corrector at its value."""
        fam, z, t, values, br = self.fam, self.z, self.t, self.values, self.br
        while (self.k_next < values.size and t[-1] * self.dirn > 0 and t_new[-1] * self.dirn > 0
               and (new_z[-1] - values[self.k_next]) * self.dirn >= 0):
            p_g = values[self.k_next]
            w_ = (p_g - z[-1]) / (new_z[-1] - z[-1]) if new_z[-1] != z[-1] else 1.0
            res = correct_fixed(fam, (1 - w_) * z[:-1] + w_ * new_z[:-1], p_g,
                                fam.scales.size(new_z[:fam.n] - z[:fam.n]) + 1e-9)
            if res is None:
                break
            gz = np.concatenate([res[0], [p_g]])
            gt = tangent(fam, res[0], p_g, prev=t)
            if gt is None:
                break
            gp = branch_point_at(fam, gz, gt, "grid", self.segment, res[1])
            gp.grid_index = self.k_next
            br.grid[self.k_next] = gp
            fam.pin(p_g, gp.y)
            br.points.append(gp)
            self.k_next += 1

    def _advance(self, new_z, t_new, newp, ds_used, t_exact_new, its):
        """Move to the new point; past a turn back too far (or out of range), jump next."""
        self.br.points.append(newp)
        self.z_prev, self.t_prev, self.ds_prev = self.z, self.t, ds_used
        self.z, self.t, self.cur, self.t_exact = new_z, t_new, newp, t_exact_new
        self.last_B = self.cur.det_B or self.last_B
        dirn = self.dirn
        self.back = self.back + abs(ds_used) if self.t[-1] * dirn < 0 else 0.0
        out_of_range = ((self.z[-1] - self.values[0]) * dirn
                        < -0.5 * self.spacing * self.fam.p_scale)
        if self.back > BACK_ARC or (self.t[-1] * dirn < 0 and out_of_range):
            self.pending_jump = True
            return
        self.ds = min(1.5 * self.ds, self.ds_max) if its <= EASY else self.ds

    def _jump(self) -> bool:
        """A fresh solve at the next grid value from the last fold (or point): a new segment."""
        jumped = _jump(self.fam, self.br, self.z if self.fold_z is None else self.fold_z,
                       self.values, self.k_next, self.restart, self.segment + 1, self.dirn)
        if jumped is None:
            return False
        (self.z, self.t, self.cur), self.segment = jumped, self.segment + 1
        self.k_next = jumped[2].grid_index + 1
        self.t_exact = True
        self._fresh()
        return True

    def _fresh(self):
        """The state at the start of a segment."""
        self.z_prev, self.t_prev, self.ds_prev = self.z, self.t, 0.0
        self.ds, self.back, self.last_B, self.fold_z = self.spacing, 0.0, self.cur.det_B, None

    def _finish(self) -> Branch:
        br = self.br
        br.record = {"steps": self.steps, "accepted": self.accepted, "rejected": self.rejected,
                     "model_builds": self.fam.evaluations, "fd_rel": FD_REL, "ctol": CTOL,
                     "corrector_iter": CORRECTOR_ITER, "step_tol": STEP_TOL,
                     "xtol_fold": self.xtol, "ds_max": self.ds_max,
                     "ds_min": DS_MIN, "reach": REACH, "back_arc": BACK_ARC, "easy": EASY,
                     "segments": self.segment + 1, "constraint_rows": int(self.fam.rows.size),
                     "constraint_rows_dropped": int(self.fam.m - self.fam.rows.size),
                     "det_undecided": int(sum(1 for b in br.points if b.det_B == 0)),
                     "tangents_by_difference": self.approx}
        return br


def _predict(z, t, z_prev, p):
    """y at p: the tangent at z, bent by the previous point of the segment when there is one
    (y ≈ y_k + a (p − p_k) + c (p − p_k)² with a = ẏ/ṗ and c fitted to z_prev), so that a
    rotation of the equilibrium is predicted to second order."""
    a = t[:-1] / t[-1]
    dp = p - z[-1]
    y = z[:-1] + a * dp
    h = z_prev[-1] - z[-1]
    if z_prev is not z and h * dp < 0 and abs(h) > 1e-12 * (abs(dp) + abs(z[-1])):
        c = (z_prev[:-1] - z[:-1] - a * h) / (h * h)
        y = y + c * dp * dp
    return y


def _switch(fam, bp, beyond, ds, stability, segment, dirn):
    """Switch to the other branch at ``bp`` when the current branch is statically unstable
    beyond it and the other is stable: (z, t, point) on the other branch, or None."""
    model = fam.model(beyond.p)
    q = beyond.y[:fam.n]
    if stability(model, q, fam.lam_full(beyond.y)) != "unstable":
        return None
    z_b = np.concatenate([bp.y, [bp.p]])
    v = second_direction(fam, z_b, bp.tangent)
    if v is None:
        return None
    for sign in (1.0, -1.0):
        res = correct_arclength(fam, z_b, sign * v, abs(ds))
        if res is None:
            continue
        z = res[0]
        pm = fam.model(z[-1])
        if stability(pm, z[:fam.n], fam.lam_full(z[:-1])) != "stable":
            continue
        t = tangent(fam, z[:-1], z[-1], prev=sign * v)
        if t is None:
            continue
        if abs(t[-1]) > 1e-12 and t[-1] * dirn < 0:
            t = -t  # continue towards the unprocessed grid values
        return z, t, branch_point_at(fam, z, t, "switch", segment, res[1])
    return None


def _jump(fam, br, z, values, k_next, restart, segment, dirn):
    """A fresh static solve at the next grid value from the last point (a snap-through)."""
    if restart is None:
        return None
    p_g = values[k_next]
    try:
        q = restart(p_g, z[:fam.n])
    except MbseigError:
        return None
    y = fam.start(q, p_g)
    t = tangent(fam, y, p_g, direction=dirn)
    if t is None:
        return None
    zz = np.concatenate([y, [p_g]])
    pt = branch_point_at(fam, zz, t, "jump", segment)
    pt.grid_index = k_next
    br.grid[k_next] = pt
    br.points.append(pt)
    br.events.append({"type": "jump", "p": float(p_g), "from": float(z[-1]), "segment": segment,
                      "point": len(br.points) - 1})
    return zz, t, pt
