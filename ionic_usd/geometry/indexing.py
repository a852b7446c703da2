"""Indexed primvar values: each distinct value once, every value used.

An indexed primvar (``primvars:normals`` + ``primvars:normals:indices``, ``primvars:st`` …)
stores values and, per corner, an index into them. The generators index their normals by
vertex and crease and the cuts write one normal per corner, so the values repeat (a flat cap's
ring, a cylinder's rows) and some go unused (a vertex on a crease keeps a value no corner
takes); NVIDIA's validator warns about both (``IndexedPrimvarChecker``: "contains repeated
values that can be indexed"; ``UnusedPrimvarChecker``: "contains values not referenced by its
indices"). :func:`distinct_values` gives the values every client expects: distinct float32
values (as written; -0.0 becomes 0.0, an equal value), all used, numbered in the order of
their first value (the generators' values follow the corners, which keeps the crate's index
compression at its best).

One sort of plain integers, no row sort: the float32 bit patterns of a row are mixed into one
64-bit key, whose low bits are replaced by the row number; these are sorted (numpy's SIMD
sort), and neighbours with equal high bits are compared value for value (where a run of one
key holds several values, that run alone is sorted by the values). Measured by
``tools/bench_shaft.py`` (the authoring column) on the 650 k normals of a 1.26 M-triangle shaft.
"""

from __future__ import annotations

import numpy as np

from ionic_usd.errors import GeometryError

__all__ = ["distinct_values"]

_MIX = (np.uint64(0x9E3779B97F4A7C15), np.uint64(0xBF58476D1CE4E5B9), np.uint64(0x94D049BB133111EB))


def _keys(rows: np.ndarray) -> np.ndarray:
    """One uint64 per row of float32 ``rows`` (u, c ≤ 3), equal for rows with equal bits;
    the high bits mixed as well as the low ones (:func:`_groups` sorts by the high bits)."""
    bits = rows.view(np.uint32).astype(np.uint64)
    h = bits[:, 0] * _MIX[0]
    for j in range(1, bits.shape[1]):
        h = (h ^ (h >> np.uint64(29))) * _MIX[j] + bits[:, j]
    h ^= h >> np.uint64(32)  # the finaliser of splitmix64: every bit reaches the high ones
    h *= _MIX[1]
    return h ^ (h >> np.uint64(29))


def _differ(bits: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(m,) bool: whether rows ``a`` and ``b`` (m,) of ``bits`` (u, c) differ, column by
    column (numpy's ``any`` along a short last axis costs several times the comparisons)."""
    ra, rb = np.take(bits, a, axis=0), np.take(bits, b, axis=0)
    out = ra[:, 0] != rb[:, 0]
    for j in range(1, bits.shape[1]):
        out |= ra[:, j] != rb[:, j]
    return out


def _groups(rows: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(order, new, first): the rows in an order where rows with equal bits are neighbours
    (``order``, (u,) int), where each group of equal rows starts in it (``new``, (u,) bool),
    and the smallest row of each group (``first``, the groups in ``order``'s order).

    One sort of plain integers: each row's key with its low bits replaced by the row number
    (so equal keys come out in row order, and the first of a run is its smallest row), then
    the neighbours with equal keys (a few: the keys of different rows rarely collide) are
    compared value for value. Rows whose truncated keys collide but whose values differ are
    sorted by their values, within their runs only."""
    n = len(rows)
    ib = max(1, n.bit_length())
    mask = np.uint64((1 << ib) - 1)
    packed = (_keys(rows) & ~mask) | np.arange(n, dtype=np.uint64)
    packed.sort()
    order = (packed & mask).astype(np.intp)
    new = np.empty(n, dtype=bool)
    new[:1] = True
    high = packed >> np.uint64(ib)
    np.not_equal(high[1:], high[:-1], out=new[1:])
    bits = rows.view(np.uint32)
    same_key = np.flatnonzero(~new[1:])  # i: sorted rows i and i + 1 share a key
    other = _differ(bits, order[same_key + 1], order[same_key])
    if other.any():  # one key, other values
        run = np.cumsum(new) - 1
        pos = np.flatnonzero(np.isin(run, run[same_key[other] + 1]))  # those runs, whole
        sub, r = bits[order[pos]], run[pos]
        lex = np.lexsort((*sub.T[::-1], r))  # stable: equal rows stay in row order
        order[pos] = order[pos][lex]
        sub, r = sub[lex], r[lex]
        fresh = np.ones(len(pos), dtype=bool)
        fresh[1:] = np.any(sub[1:] != sub[:-1], axis=1) | (r[1:] != r[:-1])
        new[pos] = fresh
    return order, new, order[new]


def distinct_values(
    values: np.ndarray, indices: np.ndarray | None
) -> tuple[np.ndarray, np.ndarray]:
    """An indexed primvar's values, each distinct (float32) row once and every one used.

    Parameters
    ----------
    values : (u, c) float, c ≤ 3 (normals, st)
    indices : (k,) int into ``values``, or None for one value per corner (``k = u``)

    Returns
    -------
    values : (w, c) float32, ``w ≤ u``: distinct rows, in the order of their first row in
        ``values`` among those the indices use
    indices : (k,) int32 with ``values_out[indices_out] == values[indices]`` (as float32)
    """
    # + 0.0 turns -0.0 into 0.0: equal values, which every reader (and numpy's ==) takes as
    # one, so they are merged (the bits of every other value are kept)
    v = np.ascontiguousarray(values, dtype=np.float32) + np.float32(0.0)
    if v.ndim != 2 or not 1 <= v.shape[1] <= 3:
        raise GeometryError(f"distinct_values: values of shape {v.shape}, expected (u, 1..3)")
    # intp once: numpy converts narrower index arrays on every fancy index
    idx = None if indices is None else np.asarray(indices).reshape(-1)
    if idx is not None and idx.dtype.kind in "iu":
        idx = idx.astype(np.intp, copy=False)
    if idx is not None and idx.size and (idx.min() < 0 or idx.max() >= len(v)):
        raise GeometryError(f"distinct_values: an index outside 0..{len(v) - 1}")
    kept = None  # the used rows, in their order (None: all)
    if idx is not None:
        used = np.zeros(len(v), dtype=bool)
        used[idx] = True
        if not used.all():
            kept = np.flatnonzero(used)
    rows = v if kept is None else v[kept]
    order, new, first = _groups(rows)
    # number the groups by their first row: a group's id counts the groups begun before it
    starts = np.zeros(len(rows), dtype=bool)
    starts[first] = True
    rank = (np.cumsum(starts) - 1).astype(np.int32)
    row_id = np.empty(len(rows), dtype=np.int32)
    row_id[order] = rank[first][np.cumsum(new) - 1]  # each sorted row: its group's number
    if kept is None:
        out = row_id if idx is None else row_id[idx]
    else:
        new_id = np.zeros(len(v), dtype=np.int32)
        new_id[kept] = row_id
        out = new_id[idx]
    return np.take(rows, np.flatnonzero(starts), axis=0), out
