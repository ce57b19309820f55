"""Elementary functions that work on floats, numpy arrays and CasADi symbols alike.

The closed forms in this package are written once and evaluated three ways: on floats (reports),
on numpy arrays (vectorised sweeps and Monte-Carlo checks) and on CasADi symbols (the NLP).
CasADi is never imported here: a value is symbolic when its type lives in the casadi module.
"""

from __future__ import annotations

import numpy as np


def is_symbolic(*values) -> bool:
    """True when any value is a CasADi expression (SX, MX or DM)."""
    return any(type(v).__module__.startswith("casadi") for v in values)


def _casadi():
    import casadi  # only reached with a CasADi argument, so casadi is already imported

    return casadi


def sin(x):
    return _casadi().sin(x) if is_symbolic(x) else np.sin(x)


def cos(x):
    return _casadi().cos(x) if is_symbolic(x) else np.cos(x)


def tan(x):
    return _casadi().tan(x) if is_symbolic(x) else np.tan(x)


def sqrt(x):
    return _casadi().sqrt(x) if is_symbolic(x) else np.sqrt(x)


def fabs(x):
    return _casadi().fabs(x) if is_symbolic(x) else np.abs(x)


def fmax(a, b):
    return _casadi().fmax(a, b) if is_symbolic(a, b) else np.maximum(a, b)


def fmin(a, b):
    return _casadi().fmin(a, b) if is_symbolic(a, b) else np.minimum(a, b)


def acos(x):
    return _casadi().acos(x) if is_symbolic(x) else np.arccos(x)


def asin(x):
    return _casadi().asin(x) if is_symbolic(x) else np.arcsin(x)


def sinh(x):
    return _casadi().sinh(x) if is_symbolic(x) else np.sinh(x)


def asinh(x):
    return _casadi().asinh(x) if is_symbolic(x) else np.arcsinh(x)


def cosh(x):
    return _casadi().cosh(x) if is_symbolic(x) else np.cosh(x)


def acosh(x):
    return _casadi().acosh(x) if is_symbolic(x) else np.arccosh(x)


def where(condition, a, b):
    """a where condition holds, else b. Both sides are evaluated (numpy and CasADi alike), so
    each must be finite everywhere: clip arguments rather than rely on the branch."""
    if is_symbolic(condition, a, b):
        return _casadi().if_else(condition, a, b)
    return np.where(condition, a, b)
