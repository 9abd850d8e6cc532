"""The stability and naming rules of a mode (DESIGN §6): the one place they are written.

Every reference motion is classified by the same rule, a *margin* against its *bound*:

- at rest and in steady motion the margin is the damping δ = −Re s of an eigenvalue and the
  bound its stability tolerance τ (:func:`mbseig.modal.bounds.tolerances`);
- for a periodic motion the margin is 1 − |μ| of a Floquet multiplier and the bound the error
  bound b of μ, so that "unstable" is |μ| − b > 1 and "stable" |μ| + b < 1.

    stable    margin > bound
    unstable  margin < −bound
    critical  otherwise (and every rigid-body mode: s = 0 within its error)

A mode is named by what it does: ``rigid-body`` (s = 0 within its error), ``overdamped`` or
``divergence`` (real: ω_d within its tolerance of 0, δ > 0 or not), ``flutter`` (an unstable
oscillation) or ``oscillatory``.
"""

from __future__ import annotations

__all__ = ["classify", "kind_of", "stability"]


def stability(margin: float, bound: float, rigid: bool = False) -> str:
    """The stability of one mode: ``margin`` (δ, or 1 − |μ|) against its ``bound``.

    Parameters
    ----------
    margin : float
        δ = −Re s of an eigenvalue, or 1 − |μ| of a Floquet multiplier.
    bound : float
        The margin's error bound (the tolerance τ, or the multiplier's bound b); ≥ 0.
    rigid : bool
        A rigid-body mode (s = 0 within its error): always "critical".

    Returns
    -------
    str
        "stable", "unstable" or "critical".

    Examples
    --------
    >>> stability(0.5, 1e-12), stability(-0.5, 1e-12), stability(1e-13, 1e-12)
    ('stable', 'unstable', 'critical')
    """
    if rigid:
        return "critical"
    return "stable" if margin > bound else "unstable" if margin < -bound else "critical"


def classify(margins, bounds, rigid=None) -> list:
    """:func:`stability` of every mode.

    Parameters
    ----------
    margins, bounds : sequence of float
        Per mode its margin and the margin's bound (:func:`stability`).
    rigid : sequence of bool, optional
        Per mode whether it is a rigid-body mode (none when omitted).

    Returns
    -------
    list of str
        One stability per mode.

    Examples
    --------
    >>> classify([1.0, -1.0, 0.0], [0.1, 0.1, 0.1], [False, False, True])
    ['stable', 'unstable', 'critical']
    """
    rigid = [False] * len(margins) if rigid is None else rigid
    return [stability(float(m), float(b), bool(r)) for m, b, r in zip(margins, bounds, rigid,
                                                                       strict=True)]


def kind_of(stability_: str, delta: float, omega_d: float, bound: float,
            rigid: bool = False) -> str:
    """What a mode does, from its stability, damping δ, damped frequency ω_d and bound.

    Parameters
    ----------
    stability_ : str
        The mode's stability (:func:`stability`).
    delta : float
        δ = −Re s.
    omega_d : float
        Im s (or the exponent's imaginary part of a Floquet multiplier).
    bound : float
        The tolerance within which ω_d reads 0 (a real mode).
    rigid : bool
        s = 0 within its error.

    Returns
    -------
    str
        "rigid-body", "overdamped", "divergence", "flutter" or "oscillatory".

    Examples
    --------
    >>> kind_of("unstable", -0.1, 3.0, 1e-9), kind_of("stable", 0.2, 0.0, 1e-9)
    ('flutter', 'overdamped')
    """
    if rigid:
        return "rigid-body"
    if abs(omega_d) <= bound:
        return "overdamped" if delta > 0 else "divergence"
    return "flutter" if stability_ == "unstable" else "oscillatory"
