"""What a person reads: the zero rule (DESIGN §6) in one place.

A value within its error bound of zero is zero wherever a person reads it: text tables,
summaries, sensitivity tables and charts, figure titles and axes, the builder's repr, the
check.  Every such place formats through :func:`shown` (the number to draw or print) or
:func:`fmt` (its text); the JSON keeps the raw value and its bound.

    shown(x, b) = 0    when |x| ≤ b      (b: the value's own error bound, ≥ 0)
                = x    otherwise

A complex value is judged part by part (each with its bound).  A NaN bound, or none, leaves the
value as it is (nothing is known to be zero); a negative zero is printed as 0.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["shown", "fmt", "fmt_complex", "shown_array"]


def shown(x, bound=None):
    """``x`` with the zero rule applied (module docstring); a complex ``x`` part by part, with
    ``bound`` a number or a (real-part bound, imaginary-part bound) pair."""
    if isinstance(x, complex) or np.iscomplexobj(x):
        z = complex(x)
        br, bi = bound if isinstance(bound, (tuple, list)) else (bound, bound)
        return complex(shown(z.real, br), shown(z.imag, bi))
    x = float(x)
    if bound is not None and not math.isnan(bound) and abs(x) <= bound:
        return 0.0
    return x + 0.0  # no negative zero


def shown_array(x, bound):
    """:func:`shown` over an array (``bound`` an array of the same shape or a number)."""
    x = np.asarray(x, float)
    b = np.broadcast_to(np.asarray(bound, float), x.shape)
    out = np.where(np.abs(x) <= np.where(np.isnan(b), -np.inf, b), 0.0, x)
    return out + 0.0


def fmt(x, bound=None, spec=".6g", *, zero="0"):
    """The text of ``x`` under the zero rule: ``zero`` when it is within its bound of 0, else
    ``format(x, spec)``."""
    v = shown(x, bound)
    if v == 0.0 and (bound is not None or x == 0):
        return zero
    return format(v, spec)


def fmt_complex(z, bound_re=None, bound_im=None, spec=".6g"):
    """'a ± bi' (or 'a', 'bi', '0') of a complex ``z`` under the zero rule, part by part."""
    v = shown(complex(z), (bound_re, bound_im))
    if v.imag == 0:
        return fmt(v.real, None, spec)
    if v.real == 0:
        return f"{format(v.imag, spec)}i"
    sign = "+" if v.imag > 0 else "−"
    return f"{format(v.real, spec)} {sign} {format(abs(v.imag), spec)}i"
