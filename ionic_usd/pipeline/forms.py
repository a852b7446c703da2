"""The column asset's ``form`` variants: a part clipped to the walls it stands in.

``full`` is the free-standing column; ``engaged`` the half column in front of a wall (the part
behind the plane z = −ENGAGED_INSET removed and capped); ``corner`` the three-quarter column
at a corner (the quadrant x, z < −ENGAGED_INSET removed). Bases and shafts are plane clips
whose cut faces meet along the same vertices (they still weld); so is the capital, with its
sliver clean-up along the cut. The corner's two walls are one notch cut
(:mod:`ionic_usd.geometry.notch`). Used by :mod:`ionic_usd.pipeline.asset`.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ionic_usd.blueprint.column_asset import ENGAGED_INSET
from ionic_usd.geometry.boolean import new_points
from ionic_usd.geometry.mesh import Mesh
from ionic_usd.geometry.slivers import SLIVER_TOL, remove_slivers

__all__ = ["form_cut", "form_cuts", "outside_walls"]


def _diagonal(mesh: Mesh) -> float:
    lo, hi = mesh.extent
    return float(
        np.linalg.norm(np.asarray(hi, dtype=np.float64) - np.asarray(lo, dtype=np.float64))
    )


def _wall_block(mesh: Mesh, x_max: float | None) -> Mesh:
    """The wall block z < −ENGAGED_INSET (and x < ``x_max`` if given) round ``mesh``."""
    from ionic_usd.temple.cuboid import Cuboid, cuboid_mesh

    lo, hi = mesh.extent
    big = float(np.abs(np.concatenate([lo, hi])).max()) + 1.0
    x1 = big if x_max is None else x_max
    return cuboid_mesh(
        Cuboid((-big, lo[1] - 1.0, -big), (x1, hi[1] + 1.0, -ENGAGED_INSET), name="wall")
    )


def _wall_cut(mesh: Mesh, x_max: float | None, simplify: bool = False) -> Mesh:
    """``mesh`` minus the wall block z < −ENGAGED_INSET (and x < ``x_max`` if given), by a
    robust boolean difference (manifold3d): the cut faces are exact planar caps."""
    from ionic_usd.geometry.boolean import difference

    return difference(mesh, [_wall_block(mesh, x_max)], name=mesh.name, simplify=simplify)


def _mended(cut: Mesh, mesh: Mesh, tol: float) -> Mesh:
    """The sliver clean-up of a capital's cut, round the points the cut made only (the rest
    is the united capital's surface, mended already)."""
    return remove_slivers(cut, tol, changed=new_points(cut.points, mesh.points))


def _engage(mesh: Mesh, part: str = "") -> Mesh:
    """The half column: the part behind the wall plane z = −ENGAGED_INSET removed.

    A plane clip capped by a constrained Delaunay triangulation (base and shaft cut faces meet
    along the same vertices, so they still weld). The capital's clip first moves the points
    within the sliver tolerance of the plane onto it (no needle between a point and the cut
    next to it), then its sliver clean-up mends the triangles round the points the cut made.
    """
    from ionic_usd.geometry.clip import clip_mesh

    plane, normal = (0.0, 0.0, -ENGAGED_INSET), (0.0, 0.0, 1.0)
    if part != "CapitalBody":
        return clip_mesh(mesh, plane, normal, name=mesh.name)
    tol = SLIVER_TOL * _diagonal(mesh)
    return _mended(clip_mesh(mesh, plane, normal, eps=tol, name=mesh.name), mesh, tol)


def _corner(mesh: Mesh, part: str = "") -> Mesh:
    """The three-quarter column: the quadrant x, z < −ENGAGED_INSET (inside the walls of a
    corner whose outer faces hold the axis) removed.

    Two plane splits capped in both wall planes (:func:`~ionic_usd.geometry.notch.cut_quadrant`),
    with the capital's snap and sliver clean-up as in :func:`_engage`; a mesh whose cut
    outline runs along the corner line itself (which those caps cannot follow) is cut by the
    robust boolean difference instead.
    """
    from ionic_usd.errors import GeometryError
    from ionic_usd.geometry.notch import cut_quadrant

    capital = part == "CapitalBody"
    tol = SLIVER_TOL * _diagonal(mesh) if capital else None
    try:
        cut = cut_quadrant(mesh, -ENGAGED_INSET, -ENGAGED_INSET, eps=tol)
    except GeometryError:
        return _wall_cut(mesh, -ENGAGED_INSET, simplify=capital)
    return cut if tol is None else _mended(cut, mesh, tol)


def form_cut(mesh: Mesh, form: str, part: str = "") -> Mesh:
    """``mesh`` clipped to a ``form`` variant: ``full`` (unchanged), ``engaged`` (behind the
    wall plane z = −ENGAGED_INSET removed, capped) or ``corner`` (the quadrant x, z <
    −ENGAGED_INSET removed)."""
    if form == "full":
        return mesh
    return {"engaged": _engage, "corner": _corner}[form](mesh, part)


def form_cuts(mesh: Mesh, forms: Sequence[str], part: str = "") -> list[Mesh]:
    """:func:`form_cut` of ``mesh`` for each of ``forms``."""
    return [form_cut(mesh, f, part) for f in forms]


def outside_walls(points: np.ndarray, form: str) -> np.ndarray:
    """(n,) bool: the points (n, 3) a ``form`` keeps (see :func:`form_cut`)."""
    behind = points[:, 2] < -ENGAGED_INSET
    if form == "engaged":
        return ~behind
    if form == "corner":
        return ~(behind & (points[:, 0] < -ENGAGED_INSET))
    return np.ones(len(points), dtype=bool)
