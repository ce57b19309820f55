"""Scrambled Sobol' points for the multistart, in numpy: the points of
`scipy.stats.qmc.Sobol(d, scramble=True, seed=seed).random(n)` bit for bit (tests/test_scale.py
compares them), without importing scipy.stats, which took 0.4 s of an optimize that spends 20 ms
in IPOPT.

The construction (Bratley and Fox; Joe and Kuo's direction numbers, whose first rows are below):
direction numbers v[d, j] from the primitive polynomial of dimension d, scrambled by a random
lower-triangular binary matrix (linear matrix scrambling) and a random digital shift, then the
Gray-code order: point i = point i-1 XOR v[:, lowest zero bit of i-1].
"""

from __future__ import annotations

import numpy as np

BITS = 30
# Joe and Kuo's new-joe-kuo-6.21201 (as scipy ships them): each dimension's primitive
# polynomial and initial direction numbers; more dimensions fall back to scipy.
POLY = (1, 3, 7, 11, 13, 19, 25, 37, 41, 47, 55, 59, 61, 67, 91, 97)
VINIT = ((1,), (1,), (1, 3), (1, 3, 1), (1, 1, 1), (1, 1, 3, 3), (1, 3, 5, 13), (1, 1, 5, 5, 17),
         (1, 1, 5, 5, 5), (1, 1, 7, 11, 19), (1, 1, 5, 1, 1), (1, 1, 1, 3, 11),
         (1, 3, 5, 5, 31), (1, 3, 3, 9, 7, 49), (1, 1, 1, 15, 21, 21), (1, 3, 1, 13, 27, 49))
MAX_DIMENSION = len(POLY)


def sobol(dimension: int, count: int, seed: int) -> np.ndarray:
    """count scrambled Sobol' points in the unit cube (count x dimension)."""
    if dimension > MAX_DIMENSION:
        from scipy.stats import qmc

        return qmc.Sobol(d=dimension, scramble=True, seed=seed).random(count)
    rng = np.random.default_rng(seed)
    powers = 2 ** np.arange(BITS, dtype=np.int64)
    shift = rng.integers(2, size=(dimension, BITS), dtype=np.uint32).astype(np.int64) @ powers
    ltm = np.tril(rng.integers(2, size=(dimension, BITS, BITS), dtype=np.uint32))
    v = _directions(dimension)
    for d in range(dimension):
        np.fill_diagonal(ltm[d], 1)
        v[d] = _scrambled(ltm[d].astype(np.int64) @ powers[::-1], v[d])
    out = np.empty((count, dimension))
    quasi = shift
    for i in range(count):
        if i:
            quasi = quasi ^ v[:, _lowest_zero_bit(i - 1)]
        out[i] = quasi / 2.0**BITS
    return out


def _directions(dimension: int) -> np.ndarray:
    v = np.zeros((dimension, BITS), dtype=np.int64)
    v[0, :] = 1
    for d in range(1, dimension):
        p = POLY[d]
        m = p.bit_length() - 1
        v[d, :m] = VINIT[d][:m]
        for j in range(m, BITS):
            new = int(v[d, j - m])
            for k in range(m):
                if (p >> (m - 1 - k)) & 1:
                    new ^= int(v[d, j - k - 1]) << (k + 1)
            v[d, j] = new
    return v << (BITS - 1 - np.arange(BITS))


def _scrambled(rows: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Each direction number multiplied (over GF(2)) by the scrambling matrix whose rows, read
    as integers, are `rows`: bit BITS-1-p of the result is the parity of rows[p] & v."""
    out = np.zeros_like(v)
    for j, vj in enumerate(v.tolist()):
        out[j] = sum((bin(int(r) & vj).count("1") & 1) << (BITS - 1 - p)
                     for p, r in enumerate(rows.tolist()))
    return out


def _lowest_zero_bit(n: int) -> int:
    i = 0
    while (n >> i) & 1:
        i += 1
    return i
