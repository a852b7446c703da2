"""The column asset's ``form`` variants: a part clipped to the walls it stands in.

``full`` is the free-standing column; ``engaged`` the half column in front of a wall (the part
behind the plane z = −ENGAGED_INSET removed and capped); ``corner`` the three-quarter column
at a corner (the quadrant x, z < −ENGAGED_INSET removed). Bases and shafts are plane clips
whose cut faces meet along the same vertices (they still weld); the capital is cut by a
robust boolean difference (manifold3d) with its sliver clean-up, its forms sharing one
operand. Used by :mod:`ionic_usd.pipeline.asset`.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ionic_usd.geometry.mesh import Mesh
from ionic_usd.usd.column_asset import ENGAGED_INSET

__all__ = ["form_cut", "form_cuts", "outside_walls"]


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


def _engage(mesh: Mesh, part: str = "") -> Mesh:
    """The half column: the part behind the wall plane z = −ENGAGED_INSET removed.

    A plane clip capped by a constrained Delaunay triangulation (base and shaft cut faces meet
    along the same vertices, so they still weld); for the capital, the boolean difference
    (its sliver clean-up keeps the cut free of needle triangles).
    """
    from ionic_usd.geometry.clip import clip_mesh

    if part == "CapitalBody":
        return _wall_cut(mesh, None, simplify=True)
    return clip_mesh(mesh, (0.0, 0.0, -ENGAGED_INSET), (0.0, 0.0, 1.0), name=mesh.name)


def _corner(mesh: Mesh, part: str = "") -> Mesh:
    """The three-quarter column: the quadrant x, z < −ENGAGED_INSET (inside the walls of a
    corner whose outer faces hold the axis) removed."""
    return _wall_cut(mesh, -ENGAGED_INSET, simplify=part == "CapitalBody")


def form_cut(mesh: Mesh, form: str, part: str = "") -> Mesh:
    """``mesh`` clipped to a ``form`` variant: ``full`` (unchanged), ``engaged`` (behind the
    wall plane z = −ENGAGED_INSET removed, capped) or ``corner`` (the quadrant x, z <
    −ENGAGED_INSET removed)."""
    if form == "full":
        return mesh
    return {"engaged": _engage, "corner": _corner}[form](mesh, part)


def form_cuts(mesh: Mesh, forms: Sequence[str], part: str = "") -> list[Mesh]:
    """:func:`form_cut` of ``mesh`` for each of ``forms``; the capital's cuts share one
    boolean operand (the same meshes as one :func:`form_cut` each)."""
    if part != "CapitalBody":
        return [form_cut(mesh, f, part) for f in forms]
    from ionic_usd.geometry.boolean import differences

    x_max = {"engaged": None, "corner": -ENGAGED_INSET}
    cut = [f for f in forms if f != "full"]
    done = differences(mesh, [[_wall_block(mesh, x_max[f])] for f in cut], mesh.name, simplify=True)
    by_form = dict(zip(cut, done, strict=True))
    return [mesh if f == "full" else by_form[f] for f in forms]


def outside_walls(points: np.ndarray, form: str) -> np.ndarray:
    """(n,) bool: the points (n, 3) a ``form`` keeps (see :func:`form_cut`)."""
    behind = points[:, 2] < -ENGAGED_INSET
    if form == "engaged":
        return ~behind
    if form == "corner":
        return ~(behind & (points[:, 0] < -ENGAGED_INSET))
    return np.ones(len(points), dtype=bool)
