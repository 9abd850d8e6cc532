"""Stage 4: modes and their stability (docs/design.md, "Tolerances").

For an eigenvalue s_k = −δ_k + iω_k:  ω_n = |s|,  ζ = δ/|s| (0 for a rigid-body mode),
f = ω/2π (``freq_hz``: the damped frequency ω_d/2π, 0 for a real eigenvalue) and
f_n = ω_n/2π (``freq_n_hz``: the natural frequency |s|/2π, what python-control's ``damp``
reports and what ``--band-hz`` and ``--target-hz`` select on), and

    δ > tol_k  stable,   |δ| ≤ tol_k  critical,   δ < −tol_k  unstable,

    tol_k = max(safety · err_k,  stability_rtol · |s_k|,  stability_atol)

where err_k is an error bound of s_k:

* a simple eigenvalue: the smaller of the normwise and the componentwise first-order bounds,
  κ·max(η, ε) and κ_c·max(η_c, ε) (:mod:`mbseig.eigen.measures`; both are valid, the second is
  much sharper for badly scaled models and exact zero patterns);
* a cluster (eigenvalues whose error discs of radius safety·err overlap, e.g. a defective double
  root computed as two eigenvalues √ε apart, or a near-real complex pair): first-order bounds are
  invalid there (κ = ∞ for an exactly defective one), so every member gets
  err = spread + S·max(η, ε)^{1/b} — the distance of the members from their mean plus the
  Hölder-type bound of a Jordan block of size b = ⌈k/g⌉ (k members, g independent eigenvectors,
  S = max(|mean|, √(‖Q‖/‖M‖))); a semisimple cluster (b = 1) keeps spread + its first-order
  bound.

The structured paths (``eigh``, ``proportional``) compute δ = (α + βω²)/2 from an accurate ω² and
supply a sharper bound of the error of Re s, which replaces err in the δ test (not in the
rigid-body and real tests).  So "δ = 0" means "zero within the numerical error of this
eigenvalue", and the tolerance of each verdict is recorded per mode: a computed eigenvalue with
Re s above its bound is never called critical or rigid-body.  Kinds: ``rigid-body`` (|s| ≤ tol: s
= 0 lies within its bound), ``oscillatory`` (complex, δ ≥ −tol), ``flutter`` (complex, δ < −tol),
``overdamped`` (real, negative), ``divergence`` (real, positive); |ω| ≤ tol counts as real.

Listing (real M, P, Q): a complex-conjugate pair once (ω > 0), real eigenvalues each; a pair with
|ω| within its tolerance (a defective or nearly defective double root, e.g. critical damping)
counts as two real eigenvalues and is listed twice with ω = 0; the rigid-body eigenvalues (s = 0,
double when P x = 0) are listed once per independent vector, the member with the largest Re s
first (a ±ε divergence pair shows its positive member).  Complex M, P, Q: every eigenvalue is
listed (no conjugate pairs).  Sorted by ω_n, then δ, then ω (deterministic).

Every listing accounts for the 2n eigenvalues of an n-DOF problem (:attr:`Modes.accounting`):
listed modes (a pair counts 2) + rigid-body eigenvalues + infinite ones = 2n; a dense listing
that does not (or a zero eigenvalue of higher multiplicity than twice its independent vectors:
secular growth tᵏ that no listed mode shows) is refused with :class:`~mbseig.errors.SolverError`.
A partial spectrum lists what it computed: its verdict is "of the modes computed" and
:attr:`Modes.coverage` says which part of the s-plane that is.
"""

from __future__ import annotations


import dataclasses

import numpy as np
import scipy.sparse as sp

from ..arguments import check
from ..eigen import Problem, Request, SingularPencilError, solve
from ..eigen.small import small_problem
from ..errors import SolverError
from ..linear import LinearModel
from ..model.symmetry import RigidDirections
from .bounds import error_bounds, tolerance_rule, tolerances, worst, zero_pair_floor
from .rules import classify, kind_of
from .listing import band_of, coordinate_text, listing, mode_shapes
from .scope import apply_scope, reduced_directions
from .small import small_modes
from .result import BAND_DENSE_MAX, DENSE_MAX, STABILITY_ORDER, Modes, Verdict

__all__ = ["Modes", "Verdict", "modes", "STABILITY_ORDER", "tolerances", "tolerance_rule",
           "classify", "kind_of", "worst"]

#: path options the fused small-dense implementation takes (others: the general stage)
FUSED_OPTIONS = frozenset({"sym_tol", "rayleigh_tol", "left", "companion_cond", "verify_tol",
                           "scale"})



def modes(M, P=None, Q=None, *, solver: str = "auto", N=None, coordinate_names=None,
          stability_rtol: float = 1e-12, stability_atol: float = 0.0, safety: float = 10.0,
          n_dominant: int = 3, rigid_rank_tol: float = 1e-6, n_modes: int | None = None,
          target: float | None = None, band=None, constraints=None, eta_warn: float = 1e-12,
          fused: bool = True, rigid=None, display=None, **solver_options) -> Modes:
    """Solve and classify the modes of (M s² + P s + Q) x = 0.

    Parameters
    ----------
    M : array_like, scipy.sparse matrix or LinearModel
        The mass matrix, or a :class:`~mbseig.linear.LinearModel` whose M, P, Q, N, coordinate
        names, rigid-body directions, display map and (large constrained models) constraint
        Jacobian are used.
    P, Q : array_like or scipy.sparse matrix, optional
        Damping (with gyroscopic terms) and stiffness; P defaults to zero.  Q is required
        unless M is a LinearModel.
    solver : str
        The eigensolver path (:data:`mbseig.eigen.SOLVERS`); "auto" chooses by structure.
    N : array_like, optional
        Null-space basis for the mode shapes in full coordinates (q = N x).
    coordinate_names : sequence of str, optional
        The names of the full coordinates (the dominant coordinates of each mode).
    stability_rtol, stability_atol : float
        The relative and absolute floors of each mode's stability tolerance
        (module docstring: τ = max(safety κ η, rtol |s|, atol)).
    safety : float
        The factor on the first-order error bound κ η.
    n_dominant : int
        How many dominant coordinates each mode lists.
    rigid_rank_tol : float
        Relative threshold for counting independent eigenvectors (rigid-body modes, Jordan block
        sizes of clusters).
    n_modes : int, optional
        A partial spectrum of sparse matrices: the ``n_modes`` modes nearest ``target``.
    target : float, optional
        The angular frequency [rad/s] the partial spectrum is nearest (default 0).
    band : tuple of float, optional
        Every mode with ω_n in ``band = (ω_lo, ω_hi)``.
    constraints : array_like or scipy.sparse matrix, optional
        Φ_q when M, P, Q are in full coordinates (partial paths).
    eta_warn : float
        A listed mode whose backward errors (normwise and componentwise) both exceed it is
        flagged in :attr:`Modes.flags` and named in a RuntimeWarning.
    fused : bool
        A small real dense problem (order ≤ :data:`mbseig.eigen.small.SMALL_MAX`, ``auto``, the
        full spectrum) takes the fused implementation of its path
        (:func:`mbseig.modal.small.small_modes`: the same numbers, a fraction of the time);
        False runs the general stage (for comparisons).
    rigid : RigidDirections, callable or array_like, optional
        The model's rigid-body directions by construction (DESIGN §6,
        :mod:`mbseig.modal.scope`): a :class:`~mbseig.model.symmetry.RigidDirections`, a callable
        returning one (called only when a mode is rigid-body), or an array whose columns are
        directions in the coordinates of the shapes.  The verdict leaves those modes out.
    display : DisplayMap or callable, optional
        The dominant coordinates named by its rows (a body's translation and rotation, a beam
        station) instead of the natural coordinates.
    **solver_options
        The path options of the request (:class:`mbseig.eigen.Request`): those of
        :func:`mbseig.eigen.solve_qep` (``sym_tol``, ``rayleigh_tol``, ``scale``, ``left``,
        ``companion_cond``) or of :func:`mbseig.eigen.solve_partial`.

    Returns
    -------
    Modes
        Per mode (a complex pair once): eigenvalue s, δ = −Re s, ω_n, ω_d, ζ, stability and kind
        (:mod:`mbseig.modal.rules`), backward error η, condition κ, tolerance τ, shape and
        dominant coordinates; ``verdict`` the worst stability of the modes it covers.

    Examples
    --------
    >>> import numpy as np
    >>> md = modes(np.eye(1), np.array([[0.2]]), np.array([[4.0]]))   # s² + 0.2 s + 4
    >>> md.verdict, round(float(md.delta[0]), 12), round(float(md.omega_n[0]), 12)
    ('stable', 0.1, 2.0)
    """
    check("modes", locals())
    if isinstance(M, LinearModel):
        lin = M
        M, P, Q, N, coordinate_names = lin.M, lin.P, lin.Q, lin.N, lin.coordinate_names
        if constraints is None:
            constraints = lin.constraint_jacobian
        if rigid is None:
            rigid = lin.rigid
        if display is None:
            display = lin.display
    if Q is None:
        raise SolverError("modes(M, P, Q) needs Q (or a LinearModel alone)")
    if (fused and solver == "auto" and n_modes is None and target is None and band is None
            and constraints is None and FUSED_OPTIONS.issuperset(solver_options)
            and small_problem(M, P, Q)):
        md = small_modes(M, P, Q, N=N, coordinate_names=coordinate_names,
                         stability_rtol=stability_rtol, stability_atol=stability_atol,
                         safety=safety, n_dominant=n_dominant, rigid_rank_tol=rigid_rank_tol,
                         eta_warn=eta_warn, options=solver_options)
        if md is not None:
            return _scoped(md, rigid, N, coordinate_names, n_dominant, display)
    request = Request(solver, n_modes=n_modes, target=target, band=band, options=solver_options)
    problem = Problem(M, P, Q, G=constraints)
    if (band is not None and n_modes is None and target is None and constraints is None
            and Request(solver).family() == "dense"
            and (not sp.issparse(M) or M.shape[0] <= BAND_DENSE_MAX)):
        # a band of a model small enough for the dense path: solve it all, list the band
        full = modes(M, P, Q, solver=solver, N=N, coordinate_names=coordinate_names,
                     stability_rtol=stability_rtol, stability_atol=stability_atol,
                     safety=safety, n_dominant=n_dominant, rigid_rank_tol=rigid_rank_tol,
                     eta_warn=eta_warn, **solver_options)
        return band_of(full, band)  # (full was scoped)
    try:
        if (request.family(problem) == "dense" and sp.issparse(M)
                and M.shape[0] > DENSE_MAX):
            raise SolverError(f"{M.shape[0]} unknowns is beyond the dense path (limit "
                              f"{DENSE_MAX}): ask for a partial spectrum (n_modes=, target= or "
                              f"band=; mbseig modes --n-modes K or --band-hz F1 F2)")
        sol = solve(problem, request)
    except SingularPencilError as exc:
        if exc.vector is None:
            raise
        raise SolverError(f"singular pencil: {coordinate_text(coordinate_names, N, exc.vector)} "
                          f"has no mass, damping or stiffness (det(M s² + P s + Q) ≡ 0, every s "
                          f"would be an eigenvalue): give it mass or a spring, "
                          f"or remove it") from None
    b = error_bounds(sol, safety=safety, stability_rtol=stability_rtol,
                     stability_atol=stability_atol, rank_tol=rigid_rank_tol)
    b = zero_pair_floor(b, sol, M, P, safety)
    md = listing(sol, b, N=N, coordinate_names=coordinate_names, n_dominant=n_dominant,
                 eta_warn=eta_warn,
                 tolerances_used={"stability_rtol": stability_rtol,
                                  "stability_atol": stability_atol, "safety": safety,
                                  "rigid_rank_tol": rigid_rank_tol, "eta_warn": eta_warn})
    del sol, b  # (the solver's vectors let go before the display map is built: 48 MB at 10⁵)
    return _scoped(md, rigid, N, coordinate_names, n_dominant, display)


def _scoped(md, rigid, N, coordinate_names, n_dominant, display=None):
    """The verdict made with the rigid-body directions by construction left out
    (:mod:`mbseig.modal.scope`); ``rigid`` is asked for them only when a mode is rigid-body."""
    names, D = (), None
    if rigid is not None and "rigid-body" in md.kind:
        got = rigid() if callable(rigid) else rigid
        if isinstance(got, RigidDirections):
            names, D = tuple(got.names), got.vectors
        else:
            D = np.asarray(got)
            names = tuple(f"declared direction {k + 1}" for k in range(D.shape[1]))
        if md.vectors.shape[0] != D.shape[0]:  # full-coordinate directions, reduced shapes
            D = reduced_directions(D, N)
    md = apply_scope(md, D, names,
                     shape_fn=lambda X: mode_shapes(X, N, coordinate_names, n_dominant))
    if display is not None and len(md) and md.shapes.shape[0]:
        from ..model.naming import dominant

        shown = display() if callable(display) else display
        if shown.T.shape[1] == md.shapes.shape[0]:
            md = dataclasses.replace(md, dominant=dominant(shown, md.shapes, n_dominant))
    return md
