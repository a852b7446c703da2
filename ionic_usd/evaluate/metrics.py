"""Curve similarity measures for comparing reference and generated profiles (paper §VII).

All functions take polylines as ``(n, d)`` float arrays with ``d`` = 2 or 3 (both curves the
same ``d``). The shared kernels live beside: :mod:`ionic_usd.evaluate.polyline` (validation,
resampling, exact node-to-curve distances) and :mod:`ionic_usd.evaluate.frechet` (the Fréchet
kernels); their public functions are re-exported here.

Naming follows shapely (``hausdorff_distance(a, b, *, densify=None)``,
``frechet_distance``). Each measure is documented as

* *discrete* (only the nodes count) or *continuous* (points on edges count too), and
* *symmetric* or *directed*.

Mapping to the paper (Konečný et al. 2016, Table 6) — the paper's names are not the standard
ones:

* paper's "weak Fréchet distance" = the largest node-to-curve distance in both directions,
  points on edges included: a Hausdorff distance, not a (weak) Fréchet distance (it ignores
  the order along the curves) → :func:`hausdorff_distance` (alias :data:`paper_weak_frechet`);
* paper's "Hausdorff distance" = the same, node to node only → :func:`node_hausdorff_distance`;
* paper's "average error" = the mean of all node-to-curve distances → :func:`average_error`.

The true Fréchet distances are offered too: :func:`discrete_frechet_distance` (Eiter–Mannila)
and :func:`frechet_distance` (continuous, Alt–Godau). For any two polylines
``discrete_frechet >= frechet >= hausdorff_distance``.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np
from scipy.spatial import cKDTree

from ionic_usd.errors import ParameterError
from ionic_usd.evaluate.frechet import (
    discrete_frechet_distance,
    frechet_bisect,
    frechet_distance,
)
from ionic_usd.evaluate.polyline import (
    PolylineIndex,
    as_curve_pair,
    curve_length,
    densify_curve,
    densify_pair,
    point_to_polyline_distances,
    resample,
    two_way_distances,
)

__all__ = [
    "CurveComparison",
    "average_error",
    "compare",
    "curve_length",
    "densify_curve",
    "directed_hausdorff_distance",
    "discrete_frechet_distance",
    "frechet_distance",
    "hausdorff_distance",
    "node_hausdorff_distance",
    "paper_weak_frechet",
    "point_to_polyline_distances",
    "resample",
]


# --------------------------------------------------------------------------------------------
# Hausdorff-type measures: a, b are (n, d) and (m, d) float polylines; each returns a float
# --------------------------------------------------------------------------------------------
def directed_hausdorff_distance(
    a: np.ndarray, b: np.ndarray, *, densify: float | None = None
) -> float:
    """Largest distance from a node of ``a`` to the curve ``b`` (edges of ``b`` included).

    Directed; discrete on ``a`` (its nodes), continuous on ``b``. ``densify`` (a fraction in
    (0, 1], as in shapely/GEOS) first splits every segment of both curves into
    ``round(1 / densify)`` parts, which converges to the fully continuous directed Hausdorff
    distance.
    """
    a, b = densify_pair(*as_curve_pair(a, b), densify)
    return float(PolylineIndex(b).distances(a).max())


def hausdorff_distance(a: np.ndarray, b: np.ndarray, *, densify: float | None = None) -> float:
    """Symmetric node-to-curve Hausdorff distance — the paper's "weak Fréchet distance".

    ``max(directed(a, b), directed(b, a))`` where each direction takes the nodes of one curve
    and the closest point of the other curve, points on its edges included (continuous on
    the target, discrete on the source nodes). This is what GEOS' ``hausdorff_distance``
    computes too. The paper calls it "weak Fréchet"; it ignores the order along the curves,
    so it is a Hausdorff distance (a lower bound of the Fréchet distances). ``densify``
    behaves as in :func:`directed_hausdorff_distance`.
    """
    da, db = two_way_distances(*densify_pair(*as_curve_pair(a, b), densify))
    return float(max(da.max(), db.max()))


#: The paper's "weak Fréchet distance" is :func:`hausdorff_distance` (the paper misnames it).
paper_weak_frechet = hausdorff_distance


def _node_distances(a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Node-to-nearest-node distances both ways (edges ignored)."""
    return cKDTree(b).query(a)[0], cKDTree(a).query(b)[0]


def node_hausdorff_distance(a: np.ndarray, b: np.ndarray) -> float:
    """Symmetric node-to-node Hausdorff distance — the paper's "Hausdorff distance".

    Discrete on both curves: the largest distance from a node of either curve to the nearest
    *node* of the other (edges ignored). Always >= :func:`hausdorff_distance`.
    """
    da, db = _node_distances(*as_curve_pair(a, b))
    return float(max(da.max(), db.max()))


def average_error(a: np.ndarray, b: np.ndarray) -> float:
    """Mean of all node-to-curve distances — the paper's "average error".

    Symmetric; discrete on the source nodes, continuous on the target curve. The distances
    of the n nodes of ``a`` to curve ``b`` and of the m nodes of ``b`` to curve ``a`` are
    pooled: ``(sum_a + sum_b) / (n + m)``.
    """
    da, db = two_way_distances(a, b)
    return float((da.sum() + db.sum()) / (da.size + db.size))


# --------------------------------------------------------------------------------------------
# the bundle (paper Table 6)
# --------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class CurveComparison:
    """All measures between two curves, as in the paper's Table 6 plus true Fréchet.

    Distances are in the curves' units (metres in this package); ``*_pct`` properties are
    percentages of ``mean_length``, as in the paper.

    Attributes
    ----------
    nodes_a, nodes_b : int
    length_a, length_b, mean_length : float
    hausdorff : float
        Node-to-curve, symmetric — the paper's "weak Fréchet".
    node_hausdorff : float
        Node-to-node, symmetric — the paper's "Hausdorff".
    average_error : float
        Mean node-to-curve distance, both directions pooled.
    discrete_frechet, frechet : float
        Discrete and continuous Fréchet distances.
    """

    nodes_a: int
    nodes_b: int
    length_a: float
    length_b: float
    mean_length: float
    hausdorff: float
    node_hausdorff: float
    average_error: float
    discrete_frechet: float
    frechet: float

    _MEASURES = ("hausdorff", "node_hausdorff", "average_error", "discrete_frechet", "frechet")

    def __post_init__(self) -> None:
        for name in ("nodes_a", "nodes_b"):
            value = getattr(self, name)
            if int(value) != value or value < 1:
                raise ParameterError(name, value, "an integer >= 1")
        for name in ("length_a", "length_b", "mean_length", *self._MEASURES):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0.0):
                raise ParameterError(name, value, "a finite number >= 0")

    def percent(self, measure: str) -> float:
        """``measure`` as a percentage of the mean curve length (NaN if that is 0)."""
        if measure not in self._MEASURES:
            raise ParameterError("measure", measure, f"one of {', '.join(self._MEASURES)}")
        if self.mean_length == 0.0:
            return math.nan
        return 100.0 * getattr(self, measure) / self.mean_length

    @property
    def hausdorff_pct(self) -> float:
        return self.percent("hausdorff")

    @property
    def node_hausdorff_pct(self) -> float:
        return self.percent("node_hausdorff")

    @property
    def average_error_pct(self) -> float:
        return self.percent("average_error")

    @property
    def discrete_frechet_pct(self) -> float:
        return self.percent("discrete_frechet")

    @property
    def frechet_pct(self) -> float:
        return self.percent("frechet")

    def as_dict(self) -> dict[str, float | int]:
        """Plain JSON-ready dict: the fields plus ``<measure>_pct`` for each measure."""
        out: dict[str, float | int] = asdict(self)
        for name in self._MEASURES:
            pct = self.percent(name)
            out[f"{name}_pct"] = None if math.isnan(pct) else pct  # type: ignore[assignment]
        return out


def compare(
    a: np.ndarray, b: np.ndarray, *, spacing: float | None = None, tol: float = 1e-7
) -> CurveComparison:
    """Compute every measure between two curves.

    Parameters
    ----------
    a, b : (n, d), (m, d) float
        E.g. reference and generated curve.
    spacing : float, optional
        If given, both curves are first :func:`resample`-d to this node spacing (the paper
        uses the same constant spacing for all curves).
    tol : float
        Relative tolerance of the continuous Fréchet distance.

    Returns
    -------
    CurveComparison
    """
    a, b = as_curve_pair(a, b)
    if spacing is not None:
        a = resample(a, spacing=spacing)
        b = resample(b, spacing=spacing)
    da, db = two_way_distances(a, b)  # nodes of a to curve b, nodes of b to curve a
    haus = float(max(da.max(), db.max()))
    nd_a, nd_b = _node_distances(a, b)
    la, lb = curve_length(a), curve_length(b)
    if not (math.isfinite(tol) and 0.0 < tol < 1.0):
        raise ParameterError("tol", tol, "a relative tolerance in (0, 1)")
    dfd = discrete_frechet_distance(a, b)
    return CurveComparison(
        nodes_a=int(a.shape[0]),
        nodes_b=int(b.shape[0]),
        length_a=la,
        length_b=lb,
        mean_length=0.5 * (la + lb),
        hausdorff=haus,
        node_hausdorff=float(max(nd_a.max(), nd_b.max())),
        average_error=float((da.sum() + db.sum()) / (da.size + db.size)),
        discrete_frechet=dfd,
        frechet=frechet_bisect(a, b, dfd, haus, tol),
    )
