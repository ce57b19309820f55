"""Random builds: deviations drawn from each tolerance's distribution, reproducibly.

Each quantity has its own random stream, a child of np.random.SeedSequence(seed) that seeds a
PCG64 generator: the child at `stream_key(name, scene)`. A scene's quantities whose builds were
drawn before the streams were keyed by name keep the children that SeedSequence(seed).spawn
gave them (the scene's Scene.stream_keys: closed, never extended); any other name gets the
child keyed 2^32 + the first four bytes of its name's SHA-256 (a big-endian integer), a key no
spawned child has, the same in every run and every installation, whatever other quantities
exist. Stream values are uniform doubles, one 64-bit step each, turned into deviations by the
inverse of the distribution's CDF; so build i's values sit at a known place in the stream
(i * stages for a quantity that applies to each part, i for a lot) and PCG64.advance jumps
there. Build i is reproduced from (seed, i, stages) alone, whatever the number of builds drawn
with it, and adding or removing a tolerance leaves the other quantities' draws unchanged.
"""

from __future__ import annotations

import hashlib

import numpy as np

from ..tolerance_model import SIGMAS_PER_TOLERANCE, Tolerance

_HALF_ULP = 2.0 ** -54  # random() gives k 2^-53, k < 2^53: shifted, never 0 and never 1
NAMED_STREAMS = 2 ** 32  # the keys of named streams start here, above every spawned child's


def stream_key(name: str, scene=None) -> int:
    """The spawn key of a quantity's random stream (module docstring): the scene's own
    (Scene.stream_keys of `scene`, a scene dataclass or its plugin.Scene) where it has one, else
    the key of its name."""
    if scene is not None:
        from ..plugin import of

        spawned = of(scene).stream_keys.get(name)
        if spawned is not None:
            return spawned
    return NAMED_STREAMS + int.from_bytes(hashlib.sha256(name.encode()).digest()[:4], "big")


def stream(seed: int, name: str, scene=None) -> np.random.PCG64:
    """The bit generator of a quantity's random stream for `seed` (at its start)."""
    root = np.random.SeedSequence(seed)
    return np.random.PCG64(np.random.SeedSequence(root.entropy,
                                                  spawn_key=(stream_key(name, scene),),
                                                  pool_size=root.pool_size))


def draw(tolerances, builds: int, stages: int, seed: int, *, scene, start: int = 0
         ) -> dict[str, np.ndarray]:
    """Deviations (SI, added to the nominal values) of builds start .. start + builds - 1 of
    `scene` (a scene dataclass or its plugin.Scene: whose streams, stream_key): shape (builds,
    stages) for a tolerance that applies to each part, (builds,) for a lot. Tolerances still to
    be allocated (no value) are refused."""
    if builds < 0 or stages < 1 or start < 0:
        raise ValueError("draw needs builds >= 0, stages >= 1 and start >= 0")
    out = {}
    for tol in tolerances:
        if tol.value is None:
            raise ValueError(f"{tol.quantity} has no value: it is to be allocated")
        each = tol.applies_to == "each"
        per_build = stages if each else 1
        bits = stream(seed, tol.quantity, scene)
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
