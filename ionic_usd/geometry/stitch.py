"""Ring stitching: the paper's triangulation of the band between two rows of vertices.

Two index arrays ``a`` and ``b`` (rows of a mesh, each with ≥ 1 vertex, no shared vertex) are
joined by a strip of triangles. Every strip triangulation is monotone: each node of ``a`` is
connected to a contiguous run of nodes of ``b``, and the right-most connection of ``a[i]`` is the
left-most connection of ``a[i + 1]``. The paper's ``sequence`` lists these connection counts:

    ``sequence[i]`` = number of nodes of ``b`` that ``a[i]`` is connected to (≥ 1).

Walking the nodes of ``a`` along their right-most connections reads the sequence off a drawn
triangulation, as the paper describes. An open band needs ``sum(sequence) == len(a) + len(b) - 1``
(``a[0]``–``b[0]`` and ``a[-1]``–``b[-1]`` are connected); a closed ring (``is_closed``, the last
vertex joins the first) needs ``sum(sequence) == len(a) + len(b)``, with ``a[0]``'s run starting
at ``b[0]`` — the rows must start at corresponding positions.

Orientation: with ``direction = +1``, ``a`` the lower row and ``b`` the upper one, both ordered
by increasing angle about +Y (see :func:`ionic_usd.geometry.curves.revolve`), the triangles
face outward (away from the axis). ``direction = -1`` reverses every triangle.
"""

from __future__ import annotations

import numpy as np

from ionic_usd.errors import ParameterError

__all__ = ["stitch", "auto_sequence", "row_parameters"]


def row_parameters(points: np.ndarray | None, n: int, is_closed: bool) -> np.ndarray:
    """Normalised arc-length parameter of each node of a row.

    Parameters
    ----------
    points : (n, d) float or None
        Node positions; ``None`` spaces the nodes uniformly.

    Returns
    -------
    (n,) float in [0, 1] (open: first 0, last 1; closed: first 0, the closing edge ends at 1)
    """
    if points is None or n == 1:
        if n == 1:
            return np.zeros(1)
        return np.arange(n) / (n if is_closed else n - 1)
    p = np.asarray(points, dtype=np.float64)
    seg = np.linalg.norm(np.diff(p, axis=0), axis=1)
    if is_closed:
        seg = np.append(seg, np.linalg.norm(p[0] - p[-1]))
    cum = np.concatenate([[0.0], np.cumsum(seg)])
    total = cum[-1]
    if total <= 0:
        return row_parameters(None, n, is_closed)
    return cum[:n] / total


def auto_sequence(u_a: np.ndarray, u_b: np.ndarray, is_closed: bool) -> np.ndarray:
    """Derive a connection sequence from the node parameters of both rows.

    Each edge of ``b`` is given to the node of ``a`` nearest to the edge's midpoint in
    parameter space (a nearest-neighbour merge of the two rows), which keeps triangles as
    close to isosceles as the rows allow.

    Parameters
    ----------
    u_a : (n,) float, non-decreasing, from :func:`row_parameters`
    u_b : (m,) float, non-decreasing

    Returns
    -------
    (n,) int64 sequence for :func:`stitch`
    """
    n, m = len(u_a), len(u_b)
    if is_closed and m == 1:
        return np.ones(n, dtype=np.int64)
    if is_closed:
        edge_mid = 0.5 * (u_b + np.append(u_b[1:], u_b[0] + 1.0))
    else:
        edge_mid = 0.5 * (u_b[:-1] + u_b[1:])
    bounds = 0.5 * (u_a[:-1] + u_a[1:])  # Voronoi boundaries between consecutive a-nodes
    # ties (equal rows) go to the lower node, so equal rows give the regular quad split
    owner = np.searchsorted(bounds, edge_mid - 1e-12, side="right")
    counts = np.bincount(owner, minlength=n)[:n]
    return counts.astype(np.int64) + 1


def stitch(
    a: np.ndarray,
    b: np.ndarray,
    *,
    direction: int = 1,
    is_closed: bool = False,
    sequence: np.ndarray | list[int] | None = None,
    a_points: np.ndarray | None = None,
    b_points: np.ndarray | None = None,
) -> np.ndarray:
    """Triangulate the band between two vertex rows.

    Parameters
    ----------
    a, b : (n,), (m,) int
        Vertex indices of the two rows (n, m ≥ 1).
    direction : {1, -1}
        Winding, see the module docstring.
    is_closed : bool
        The rows are closed rings.
    sequence : (n,) int, optional
        Connections of each node of ``a`` to nodes of ``b``. Derived with
        :func:`auto_sequence` when omitted (from ``a_points``/``b_points`` arc lengths if
        given, else from uniform spacing).
    a_points, b_points : (n, 3), (m, 3) float, optional
        Positions used only to derive the default sequence.

    Returns
    -------
    (t, 3) int32 triangles; ``t = n + m - 2`` (open) or ``n + m`` (closed).
    """
    a = np.asarray(a, dtype=np.int64).reshape(-1)
    b = np.asarray(b, dtype=np.int64).reshape(-1)
    n, m = len(a), len(b)
    if n < 1 or m < 1:
        raise ParameterError("rows", (n, m), "each row with at least 1 vertex", context="stitch")
    if direction not in (1, -1):
        raise ParameterError("direction", direction, "1 or -1", context="stitch")
    if np.intersect1d(a, b).size:
        raise ParameterError(
            "rows", "shared vertices", "two rows without common vertices", context="stitch"
        )
    if sequence is None:
        sequence = auto_sequence(
            row_parameters(a_points, n, is_closed),
            row_parameters(b_points, m, is_closed),
            is_closed,
        )
    seq = _checked_sequence(sequence, n, m, is_closed)
    # start of each a-node's run of b-nodes
    start = np.concatenate([[0], np.cumsum(seq - 1)[:-1]])
    # fan triangles (apex on a, base edge on b)
    nfan = seq - 1
    owner = np.repeat(np.arange(n), nfan)
    k = np.arange(nfan.sum()) - np.repeat(np.cumsum(nfan) - nfan, nfan)
    j0 = (start[owner] + k) % m
    j1 = (start[owner] + k + 1) % m
    fan = np.stack([a[owner], b[j1], b[j0]], axis=1)
    # triangles with base edge on a (apex on b): a[i], a[i+1], b[last connection of a[i]]
    last = (start + seq - 1) % m
    nlow = (0 if n == 1 else n) if is_closed else n - 1
    i = np.arange(nlow)
    low = np.stack([a[i], a[(i + 1) % n], b[last[i]]], axis=1)
    tri = np.concatenate([fan, low]).astype(np.int32)
    if direction == -1:
        tri = tri[:, ::-1]
    return np.ascontiguousarray(tri)


def _checked_sequence(sequence, n: int, m: int, is_closed: bool) -> np.ndarray:
    """``sequence`` as int64, checked: one count >= 1 per node of a, summing to the band's
    number of connections."""
    seq = np.asarray(sequence, dtype=np.int64).reshape(-1)
    # a closed ring against a single vertex is a fan (a cone tip or a cap centre)
    want = (n + m - (m == 1)) if is_closed else n + m - 1
    if len(seq) != n:
        raise ParameterError(
            "sequence", f"{len(seq)} numbers", f"one number per node of a ({n})", context="stitch"
        )
    if seq.min() < 1:
        raise ParameterError("sequence", seq.tolist(), "every count >= 1", context="stitch")
    if int(seq.sum()) != want:
        raise ParameterError(
            "sequence",
            f"sum {int(seq.sum())}",
            f"sum == {want} for {'closed' if is_closed else 'open'} rows of {n} and {m}",
            context="stitch",
        )
    return seq
