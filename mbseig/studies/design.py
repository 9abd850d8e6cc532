"""Design answers: eigenvalue sensitivities to the case's parameters, modal energy shares
(``mbseig modes --json --sensitivities / --energy``; DESIGN §8; docs/design.md "Eigenvalue
sensitivities and modal energy").

Sensitivities.  For a simple eigenvalue s of T(s) = M s² + P s + Q with right vector x and left
vector y (yᴴ T(s) = 0),

    ∂s/∂p = − yᴴ (s² M_p + s P_p + Q_p) x / yᴴ (2 s M + P) x,

where M_p, P_p, Q_p are the derivatives of the *reduced* matrices with the equilibrium moving
with p (inverse-statics commands re-resolved) and the null-space basis continuous in p: the
basis of :func:`mbseig.linear.continuous_null_basis` with the independent coordinates held at
the analysed point's.  Any smooth family of bases gives the same ∂s/∂p (the reduced pencils are
congruent), so only continuity matters.  The matrix derivatives are central differences of the
whole model → equilibrium → linearization chain with step h = REL_STEP·|p| (ABS_STEP when
p = 0): truncation O(h²), and the equilibrium's own error enters as (its tolerance)/h; the
eigenvalue derivative itself is the analytic first-order formula above (no eigenvalues are
differenced).  A parameter "enters the model" when one of M, P, Q changes between p ± h;
parameters written as integers (counts, indices) and as expressions (derived values) are left
out.

Error bound of ∂s/∂p (for the zero rule, DESIGN §6): the reduced matrices at p ± h are known
to a relative ρ = max(the equilibrium's xtol, 64 ε), so their central difference errs by at most
ρ w(s)/h, w(s) = |s|²‖M‖ + |s|‖P‖ + ‖Q‖, and the formula carries that by ‖x‖‖y‖/|yᴴT'(s)x|;
the O(h²) truncation is below it at h = REL_STEP·|p|.  A rigid-body mode by construction has
∂s/∂p = 0 exactly.

Modal energy.  For mode k with full-coordinate shape φ = N x (complex), the time-averaged
energies of a part with matrix A are proportional to Re(φᴴ A φ):

* kinetic: each body and point mass (its block of M; batched or flexible masses together as
  "other masses");
* potential: each spring, torsional element and load with stiffness (its K_e = −∂g_e/∂q; a
  follower load's K_e is not symmetric, Re(φᴴ K_e φ) is its share of the work), each
  constraint's Σ λ ∇²Φ, and gravity: λ₀ = (Φ_q Φ_qᵀ)⁺ Φ_q g(q₀) splits linearly over the loads,
  so λ_grav = (Φ_q Φ_qᵀ)⁺ Φ_q g_grav carries gravity and H(λ_grav) is gravity's stiffness (in
  natural coordinates gravity is a constant force and acts only through the constraints); each
  constraint keeps H(λ₀ − λ_grav).

Shares are the parts divided by their sum (Σ = Re(xᴴ M x), Re(xᴴ Q x) in reduced coordinates),
so each dict sums to 1; a negative share (a destabilizing preload) is kept.  A mode whose total
is zero within rounding, and the potential of a rigid-body mode by construction (DESIGN §6),
get an empty dict.
"""

from __future__ import annotations

import numpy as np

from ..errors import CaseError
from ..linear import linearize
from ..model.base import BatchForce
from ..numerics import element_name
from .pipeline import analyze, as_spec
from .point import equilibrium_stage

__all__ = ["eigen_sensitivities", "modal_energy", "sensitivity_parameters", "REL_STEP",
           "ABS_STEP"]

REL_STEP = 1e-5
ABS_STEP = 1e-6


def sensitivity_parameters(spec, config=None, params=None) -> dict:
    """{name: value} of the real parameters as given (after the configuration and overrides):
    numbers written as floats; integers and expressions are left out (module docstring).  An
    override (``--param k=2000``) of a float parameter stays in, as does a float literal."""
    raw = dict(spec.parameters)
    if config is not None:
        raw.update({k: v for k, v in spec.configurations.get(config, {}).items()
                    if k != "description"})
    out = {k: float(v) for k, v in raw.items() if isinstance(v, float)}
    for k, v in (params or {}).items():  # overrides (--param gives strings)
        was_float = out.pop(k, None) is not None or isinstance(raw.get(k), float)
        if isinstance(v, bool):
            continue
        if isinstance(v, str):
            try:
                x = float(v)
            except ValueError:
                continue  # an expression: derived
            if was_float or not v.strip().lstrip("+-").isdigit():
                out[k] = x  # a float parameter, or a float literal
        elif isinstance(v, float) or (isinstance(v, int) and was_float):
            out[k] = float(v)
    return out


def _reduced(spec, config, params, reference):
    model = spec.build(config, **params)
    eq = equilibrium_stage(model)
    lin = linearize(model, eq, reference=reference or None, sparse=False)
    return tuple(np.asarray(A, float) for A in (lin.M, lin.P, lin.Q))


def _left_vector(T):
    """y with yᴴ T ≈ 0: the left singular vector of T's smallest singular value."""
    U, _, _ = np.linalg.svd(T)
    return U[:, -1]


def eigen_sensitivities(case_spec, *, config=None, params=None, analysis=None,
                        parameters=None, with_bounds=False):
    """{parameter: complex array ∂s/∂p aligned with the listed modes} (module docstring);
    with ``with_bounds``, ``(values, bounds)`` with bounds {parameter: float array}: the
    absolute error bound of each ∂s/∂p (module docstring, "Error bound"), for the zero rule.

    case_spec : a path or a :class:`~mbseig.casefile.CaseSpec`; ``analysis`` (the
    :class:`~mbseig.studies.Analysis` of the same case, configuration and parameters) is
    computed when not given.  ``parameters``: only these names (default: every real
    parameter that enters the model).
    """
    spec = as_spec(case_spec)
    params = dict(params or {})
    a = analysis if analysis is not None else analyze(spec, config=config, params=params)
    lin, md = a.linear, a.modes
    if lin.N is None or lin.B is None:
        raise CaseError("sensitivities need the dense linear model (a sparse model was "
                        "linearized)", element="--sensitivities")
    M, P, Q = (np.asarray(A, float) for A in (lin.M, lin.P, lin.Q))
    X = md.vectors
    s = md.eigenvalues
    n = M.shape[0]
    Y = np.empty_like(X, dtype=complex)
    den = np.empty(s.size, complex)
    for k in range(s.size):
        y = _left_vector(s[k] ** 2 * M + s[k] * P + Q)
        Y[:, k] = y
        den[k] = np.conj(y) @ ((2 * s[k] * M + P) @ X[:, k])
    ref = lin.independent if (lin.independent and len(lin.independent) == n) else None
    out = {}
    candidates = sensitivity_parameters(spec, config, params)
    if parameters is not None:
        unknown = [p for p in parameters if p not in candidates]
        if unknown:
            raise CaseError(f"{unknown[0]!r} is not a real parameter of the case (known: "
                            f"{', '.join(candidates) or 'none'})", element="sensitivities")
        candidates = {p: candidates[p] for p in parameters}
    bounds = {}
    rho = max(float(a.eq.tolerances.get("xtol", 0.0)), 64 * np.finfo(float).eps)
    nM, nP, nQ = (float(np.linalg.norm(A, 2)) for A in (M, P, Q))
    w = np.abs(s) ** 2 * nM + np.abs(s) * nP + nQ
    with np.errstate(divide="ignore", invalid="ignore"):
        gain = np.linalg.norm(X, axis=0) * np.linalg.norm(Y, axis=0) / np.abs(den)
    rigid = np.array([bool(r) for r in (md.rigid_body or [None] * s.size)])
    for name, value in candidates.items():
        h = REL_STEP * abs(value) if value != 0 else ABS_STEP
        plus = _reduced(spec, config, {**params, name: value + h}, ref)
        minus = _reduced(spec, config, {**params, name: value - h}, ref)
        dM, dP, dQ = ((p_ - m_) / (2 * h) for p_, m_ in zip(plus, minus, strict=True))
        scale = max(np.abs(M).max(), np.abs(P).max(), np.abs(Q).max(), 1e-300)
        if max(np.abs(p_ - m_).max() for p_, m_ in zip(plus, minus, strict=True)) <= 1e-14 * scale:
            continue  # does not enter the model
        ds = np.empty(s.size, complex)
        for k in range(s.size):
            Tp = s[k] ** 2 * dM + s[k] * dP + dQ
            with np.errstate(divide="ignore", invalid="ignore"):
                ds[k] = -(np.conj(Y[:, k]) @ (Tp @ X[:, k])) / den[k]
        out[name] = ds
        # the central difference of matrices each known to ρ of their size: ρ w(s) / h, through
        # the first-order formula (‖x‖‖y‖ / |yᴴ T'(s) x|); a rigid-body mode by construction
        # stays at s = 0 whatever p, so its ∂s/∂p is 0 and any computed value is residue
        b = np.where(np.isfinite(gain), gain * rho * w / h, np.inf)
        bounds[name] = np.where(rigid, np.maximum(b, np.abs(ds)), b)
    return (out, bounds) if with_bounds else out


def _shares(parts):
    total = sum(parts.values())
    scale = sum(abs(v) for v in parts.values())
    if scale == 0 or abs(total) <= 1e-12 * scale:
        return {}
    return {k: float(v / total) for k, v in parts.items()}


def modal_energy(model, eq, lin, modes_obj) -> list:
    """One ``{"kinetic": {name: share}, "potential": {name: share}}`` per listed mode
    (module docstring).  ``model`` is the model the equilibrium belongs to (``Analysis.model``)."""
    if lin.N is None:
        raise CaseError("modal energy needs the dense linear model", element="--energy")
    q0, lam0 = lin.q0, lin.lam0
    n = model.n
    zero = np.zeros(n)
    Mfull = model.mass_matrix(q0).toarray()
    mass_parts = []
    covered = np.zeros_like(Mfull)
    for name, idx, _, block in getattr(model, "mass_parts", ()) or ():
        mass_parts.append((name, idx, np.asarray(block)))
        covered[np.ix_(idx, idx)] += block
    rest_M = Mfull - covered
    if np.abs(rest_M).max(initial=0.0) > 1e-14 * max(np.abs(Mfull).max(initial=0.0), 1e-300):
        mass_parts.append(("other masses", np.arange(n), rest_M))
    # potential: force elements, gravity through the constraints, constraints
    pot_parts = []
    for f in model.forces:
        if isinstance(f, BatchForce):
            import scipy.sparse as sp

            Kt, _ = f.jacobian_coo(q0, zero)
            K = sp.coo_matrix((Kt[2], (Kt[0], Kt[1])), shape=(n, n)).toarray()
            pot_parts.append(("springs (batched)", np.arange(n), K))
            continue
        K, _ = f.jacobians(q0, zero)
        if np.any(K != 0):
            pot_parts.append((element_name(f.name), f.idx, np.asarray(K)))
    if model.n_constraints and lin.constraint_stiffness:
        G = model.phi_q(q0).toarray()
        lam_g = np.zeros(model.n_constraints)
        g_grav = getattr(model, "gravity_force", None)
        if g_grav is not None and np.any(g_grav):
            # the Euclidean left inverse of Φ_qᵀ, as λ₀ itself (minimum norm)
            lam_g = np.linalg.pinv(G @ G.T) @ (G @ g_grav)
            pot_parts.append(("gravity", np.arange(n),
                              model.constraint_hessian(q0, lam_g).toarray()))
        off = np.cumsum([0] + [c.n_eq for c in model.constraints])
        for k, c in enumerate(model.constraints):
            lam_c = (lam0 - lam_g)[off[k]:off[k + 1]]
            H = c.hess(q0, lam_c)
            if np.any(H != 0):
                pot_parts.append((element_name(c.name), c.idx, np.asarray(H)))
    out = []
    shapes = lin.N @ modes_obj.vectors
    for k in range(len(modes_obj)):
        phi = shapes[:, k]
        kin, pot = {}, {}
        for name, idx, A in mass_parts:
            v = phi[idx]
            kin[name] = kin.get(name, 0.0) + float(np.real(np.conj(v) @ (A @ v)))
        for name, idx, A in pot_parts:
            v = phi[idx]
            pot[name] = pot.get(name, 0.0) + float(np.real(np.conj(v) @ (A @ v)))
        rigid = bool(modes_obj.rigid_body and modes_obj.rigid_body[k])
        # a rigid-body mode by construction stores no potential energy (its parts cancel
        # exactly: each element is blind to it or turns with it, mbseig.model.symmetry)
        out.append({"kinetic": _shares(kin), "potential": {} if rigid else _shares(pot)})
    return out

