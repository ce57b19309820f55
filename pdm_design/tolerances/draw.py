"""Random builds: deviations drawn from each tolerance's distribution, reproducibly.

Each quantity has its own random stream: np.random.SeedSequence(seed).spawn gives one child per
name of model.STREAM_ORDER (a fixed order), and the child seeds a PCG64 generator. Stream values
are uniform doubles, one 64-bit step each, turned into deviations by the inverse of the
distribution's CDF; so build i's values sit at a known place in the stream (i * stages for a
quantity that applies to each part, i for a lot) and PCG64.advance jumps there. Build i is
reproduced from (seed, i, stages) alone, whatever the number of builds drawn with it, and
adding or removing a tolerance leaves the other quantities' draws unchanged.
"""

from __future__ import annotations

import numpy as np

from .model import SIGMAS_PER_TOLERANCE, STREAM_ORDER, Tolerance

_HALF_ULP = 2.0 ** -54  # random() gives k 2^-53, k < 2^53: shifted, never 0 and never 1


def draw(tolerances, builds: int, stages: int, seed: int, *, start: int = 0
         ) -> dict[str, np.ndarray]:
    """Deviations (SI, added to the nominal values) of builds start .. start + builds - 1:
    shape (builds, stages) for a tolerance that applies to each part, (builds,) for a lot.
    Tolerances still to be allocated (no value) are refused."""
    if builds < 0 or stages < 1 or start < 0:
        raise ValueError("draw needs builds >= 0, stages >= 1 and start >= 0")
    children = np.random.SeedSequence(seed).spawn(len(STREAM_ORDER))
    out = {}
    for tol in tolerances:
        if tol.value is None:
            raise ValueError(f"{tol.quantity} has no value: it is to be allocated")
        each = tol.applies_to == "each"
        per_build = stages if each else 1
        bits = np.random.PCG64(children[STREAM_ORDER.index(tol.quantity)])
        bits.advance(start * per_build)
        u = np.random.Generator(bits).random(builds * per_build) + _HALF_ULP
        values = deviations(tol, u)
        out[tol.quantity] = values.reshape(builds, stages) if each else values
    return out


def deviations(tol: Tolerance, u: np.ndarray) -> np.ndarray:
    """Deviations with uniform numbers u in (0, 1) put through the inverse CDF."""
    if tol.distribution == "uniform":
        return tol.value * (2.0 * u - 1.0)
    from scipy.special import ndtri

    return (tol.value / SIGMAS_PER_TOLERANCE) * ndtri(u)
