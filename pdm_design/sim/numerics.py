"""Small scalar numerics for the simulator, in plain Python (no scipy import on the fast path).

Importing scipy.optimize or scipy.integrate costs about 0.4 s (scipy._lib pulls in linalg and
array_api_compat); a one-design `pdm-design optimize` needs only a bracketed 1-D root and the
swing time of a pendulum, so both are here:

* `brentq`: Brent's method, a line-by-line port of scipy's C `brentq` (scipy/optimize/Zeros/
  brentq.c): same steps, same stopping rule, so the same root to the last bit
  (tests/test_extremes.py checks it against scipy on random brackets).
* `carlson_rf`: Carlson's symmetric elliptic integral R_F(x, y, z) by the duplication theorem
  (B. C. Carlson, "Numerical computation of real or complex elliptic integrals", Numer.
  Algorithms 10, 1995, algorithm for R_F, truncation error < 3e-16 relative). A pendulum's
  swing time, l dth / v(th), integrates in closed form to R_F (a scene's swing_time).
"""

from __future__ import annotations

import math

_EPS = 2.220446049250313e-16
BRENT_RTOL = 4 * _EPS  # scipy's smallest accepted rtol


class RootError(ValueError):
    """The bracket does not contain a sign change, or the iteration did not converge."""


def brentq(f, xa: float, xb: float, *, xtol: float = 2e-12, rtol: float = BRENT_RTOL,
           maxiter: int = 100) -> float:
    """Root of f on [xa, xb] (f(xa), f(xb) of opposite signs) to |error| <= xtol + rtol |x|."""
    xpre, xcur = float(xa), float(xb)
    xblk = fblk = spre = scur = 0.0
    fpre, fcur = f(xpre), f(xcur)
    if fpre == 0.0:
        return xpre
    if fcur == 0.0:
        return xcur
    if math.isnan(fpre) or math.isnan(fcur) or (fpre > 0.0) == (fcur > 0.0):
        raise RootError(f"f({xpre!r}) = {fpre!r} and f({xcur!r}) = {fcur!r} do not bracket a root")
    for _ in range(maxiter):
        if fpre != 0.0 and fcur != 0.0 and (fpre < 0.0) != (fcur < 0.0):
            xblk, fblk = xpre, fpre
            spre = scur = xcur - xpre
        if abs(fblk) < abs(fcur):
            xpre, xcur, xblk = xcur, xblk, xcur
            fpre, fcur, fblk = fcur, fblk, fcur
        delta = 0.5 * (xtol + rtol * abs(xcur))
        sbis = 0.5 * (xblk - xcur)
        if fcur == 0.0 or abs(sbis) < delta:
            return xcur
        if abs(spre) > delta and abs(fcur) < abs(fpre):
            if xpre == xblk:  # interpolate
                stry = -fcur * (xcur - xpre) / (fcur - fpre)
            else:  # extrapolate (inverse quadratic)
                dpre = (fpre - fcur) / (xpre - xcur)
                dblk = (fblk - fcur) / (xblk - xcur)
                stry = -fcur * (fblk * dblk - fpre * dpre) / (dblk * dpre * (fblk - fpre))
            if 2.0 * abs(stry) < min(abs(spre), 3.0 * abs(sbis) - delta):
                spre, scur = scur, stry  # good short step
            else:
                spre = scur = sbis  # bisect
        else:
            spre = scur = sbis
        xpre, fpre = xcur, fcur
        if abs(scur) > delta:
            xcur += scur
        else:
            xcur += delta if sbis > 0.0 else -delta
        fcur = f(xcur)
        if math.isnan(fcur):
            raise RootError(f"f({xcur!r}) is nan inside the bracket")
    raise RootError(f"no convergence in {maxiter} iterations on [{xa!r}, {xb!r}]")


# Carlson (1995): iterate until the scaled spread of the arguments is small, then sum the
# series in E2, E3. With the terms through degree 7 the truncation error is O(spread^8), so the
# spread need only fall below (3 r)^(1/8), r = 2^-53 (one duplication fewer than the degree-5
# series needs; tests/test_extremes.py checks 4e-15 against mpmath over 400 decades).
_RF_Q = (3.0 * 2.0 ** -53) ** (-1.0 / 8.0)


def carlson_rf(x: float, y: float, z: float) -> float:
    """R_F(x, y, z) = 1/2 int_0^inf dt / sqrt((t+x)(t+y)(t+z)); x, y, z >= 0, at most one 0.

    Homogeneous of degree -1/2; R_F(x, x, x) = 1/sqrt(x). Returns inf when two arguments are 0
    (the integral diverges)."""
    if min(x, y, z) < 0.0:
        raise ValueError(f"carlson_rf needs non-negative arguments, not {(x, y, z)!r}")
    if (x == 0.0) + (y == 0.0) + (z == 0.0) >= 2:
        return math.inf
    # scale by the geometric mean of the largest and the smallest non-zero argument: the scaled
    # arguments lie in [1e-162, 1e162], so their products neither overflow nor underflow
    top, bottom = max(x, y, z), min(v for v in (x, y, z) if v > 0.0)
    scale = math.sqrt(top) * math.sqrt(bottom)
    x, y, z = x / scale, y / scale, z / scale
    # with A0 the mean and Q = _RF_Q max|A0 - x_i|, iterate until 4^-n Q < |A_n|; each step
    # shrinks the spread of the arguments 4-fold: at most ~540 steps for 1e-308 .. 1e308.
    x0, y0 = x, y
    a0 = mean = (x + y + z) / 3.0
    q = _RF_Q * max(abs(a0 - x), abs(a0 - y), abs(a0 - z))
    shrink = 1.0
    for _ in range(1100):
        if q * shrink < abs(mean):
            break
        sx, sy, sz = math.sqrt(x), math.sqrt(y), math.sqrt(z)
        lam = sx * (sy + sz) + sy * sz
        x, y, z = 0.25 * (x + lam), 0.25 * (y + lam), 0.25 * (z + lam)
        mean = 0.25 * (mean + lam)
        shrink *= 0.25
    dx, dy = (a0 - x0) * shrink / mean, (a0 - y0) * shrink / mean
    dz = -(dx + dy)
    e2 = dx * dy - dz * dz
    e3 = dx * dy * dz
    series = (1.0 - e2 / 10.0 + e3 / 14.0 + e2 * e2 / 24.0 - 3.0 * e2 * e3 / 44.0
              - 5.0 * e2 * e2 * e2 / 208.0 + 3.0 * e3 * e3 / 104.0 + e2 * e2 * e3 / 16.0)
    return series / math.sqrt(mean) / math.sqrt(scale)
