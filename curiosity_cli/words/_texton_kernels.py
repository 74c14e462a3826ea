"""Numba kernels for texton words: nearest-centre assignment.

Private: call :func:`curiosity_cli.words.textons.nearest_centres`, which validates inputs
and fixes dtypes and layout. Every kernel has a slow reference twin in
``tests/naive_textons.py``.
"""

from __future__ import annotations

import numpy as np
from numba import prange

from curiosity_cli._numba import njit

# Unit roundoff of float32 (half an ulp of 1.0).
_U32 = 2.0**-24
# Rows are split into chunks of this many; a chunk is one unit of parallel work with its
# own scratch arrays. A fixed size (not one per thread) keeps the split, and so the
# scratch reuse, the same for any thread count; each row's result depends on that row only.
_CHUNK = 512
# Above this squared scale the float32 screen could overflow; such rows are assigned by
# plain float64 brute force instead.
_MAX_SCALE2 = 1e30
# Absolute error allowance of the float32 screen for values so small that they underflow.
_TINY = 1e-36


@njit(parallel=True)
def nearest_centres_kernel(vectors, centres):
    """Index of the nearest centre (squared Euclidean distance) for every vector.

    Parameters
    ----------
    vectors : (N, D) ndarray of float32, C-contiguous, finite
    centres : (K, D) ndarray of float32, C-contiguous, finite, K >= 1

    Returns
    -------
    (N,) ndarray of int32
        ``argmin_k sum_j (float64(vectors[n, j]) - float64(centres[k, j]))**2``, the sum
        taken in float64 from ``j = 0`` upward; among equal distances the lowest ``k``.

    Notes
    -----
    Two stages per vector ``v``:

    1. A float32 screen evaluates ``w_k = ||c_k||^2 + ||v||^2 + s - 2 v.c_k`` for all
       centres with SIMD-friendly loops. ``w_k`` equals ``||v - c_k||^2 + s`` up to an
       error of at most ``err = 1.1 (D + 4) u R^2`` (``u`` float32 unit roundoff,
       ``R = ||v|| + max_k ||c_k||``: the standard bound for a sum of ``D + 4`` rounded
       terms). The shift ``s = 2 err`` makes every ``w_k`` positive, so the bit patterns,
       read as int32, sort like the floats and the minimum is an integer reduction, which
       vectorises where a float one does not (it would need fast-math).
    2. Every centre with ``w_k <= min(w) + 3 err`` could be the exact nearest one (the
       3 err covers both screen errors and the float64 rounding of the exact distances),
       so the answer is the exact float64 argmin over those candidates. Usually there is
       one candidate and it is the answer without further work; duplicate or nearly
       equidistant centres give several, and then exact distances decide, ties going to
       the lowest index.

    The result is therefore the float64 brute-force argmin, not an approximation of it.
    """
    n, d = vectors.shape
    c64, ct, cn, cnorm = _prepare_centres(centres)
    kp = cn.shape[0]
    gamma = 1.1 * (d + 4) * _U32
    out = np.empty(n, np.int32)
    n_chunks = (n + _CHUNK - 1) // _CHUNK
    for chunk in prange(n_chunks):
        w = np.empty(kp, np.float32)
        w_bits = w.view(np.int32)
        cell = np.empty(1, np.float32)
        cell_bits = cell.view(np.int32)
        v = np.empty(d)
        t = np.empty(d, np.float32)
        for row in range(chunk * _CHUNK, min(n, (chunk + 1) * _CHUNK)):
            vn = 0.0
            for j in range(d):
                v[j] = np.float64(vectors[row, j])
                # exact: doubling a float32 only changes its exponent
                t[j] = np.float32(-2.0) * vectors[row, j]
                vn += v[j] * v[j]
            scale = np.sqrt(vn) + cnorm
            scale2 = scale * scale
            if scale2 > _MAX_SCALE2:
                out[row] = _exact_argmin(v, c64, -1)
                continue
            err = gamma * scale2 + _TINY
            _screen(w, cn, ct, t, np.float32(vn + 2.0 * err))

            lowest = np.int32(2147483647)
            for c in range(kp):
                lowest = min(lowest, w_bits[c])
            cell_bits[0] = lowest
            cell[0] = np.float32(np.float64(cell[0]) + 3.0 * err)
            limit = cell_bits[0]

            count = 0
            index_sum = 0
            for c in range(kp):
                hit = 1 if w_bits[c] <= limit else 0
                count += hit
                index_sum += c * hit
            if count == 1:
                out[row] = index_sum
            else:
                out[row] = _exact_argmin(v, c64, limit, w_bits)
    return out


@njit
def _prepare_centres(centres):
    """Float64 copy, float32 transposed copy padded to a multiple of 8, squared norms."""
    k, d = centres.shape
    kp = (k + 7) // 8 * 8
    c64 = np.empty((k, d))
    ct = np.zeros((d, kp), np.float32)
    # padding centres sit at a huge distance, so they never become the minimum
    cn = np.full(kp, np.float32(1e38))
    largest = 0.0
    for c in range(k):
        s = 0.0
        for j in range(d):
            x = np.float64(centres[c, j])
            c64[c, j] = x
            ct[j, c] = centres[c, j]
            s += x * x
        cn[c] = s
        largest = max(largest, s)
    return c64, ct, cn, np.sqrt(largest)


@njit
def _screen(w, cn, ct, t, shift):
    """``w[k] = cn[k] + shift + sum_j t[j] * ct[j, k]`` in float32.

    Four dimensions per pass over ``w``: one pass per dimension would be bound by loads
    and stores of ``w``.
    """
    kp = w.shape[0]
    d = t.shape[0]
    for c in range(kp):
        w[c] = cn[c] + shift
    j = 0
    while j + 4 <= d:
        t0 = t[j]
        t1 = t[j + 1]
        t2 = t[j + 2]
        t3 = t[j + 3]
        r0 = ct[j]
        r1 = ct[j + 1]
        r2 = ct[j + 2]
        r3 = ct[j + 3]
        for c in range(kp):
            w[c] += (t0 * r0[c] + t1 * r1[c]) + (t2 * r2[c] + t3 * r3[c])
        j += 4
    while j < d:
        tj = t[j]
        rj = ct[j]
        for c in range(kp):
            w[c] += tj * rj[c]
        j += 1


@njit
def _exact_argmin(v, c64, limit, w_bits=None):
    """Float64 argmin of ``||v - c||^2`` over the centres whose screen value passes ``limit``.

    With ``w_bits`` None, over all centres. Visits centres in index order and only
    replaces the best on a strictly smaller distance, so ties go to the lowest index.
    """
    d = v.shape[0]
    best = np.inf
    best_index = -1
    for c in range(c64.shape[0]):
        if w_bits is not None and w_bits[c] > limit:
            continue
        s = 0.0
        for j in range(d):
            diff = v[j] - c64[c, j]
            s += diff * diff
        if s < best:
            best = s
            best_index = c
    return best_index
