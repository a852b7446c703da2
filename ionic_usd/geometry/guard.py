"""Generator guards: a generator returns a closed, outward, finite solid or raises an error
naming the parameter that made it impossible.

Grammars and parameter ranges accept many inputs whose geometry is still impossible (a base
whose every module has zero height, a scroll whose rings all have radius 0, a profile that
turns inside out). Rather than patch each generator for each such case, every part goes
through :func:`guarded`: floating-point faults inside the generator (overflow, division by
zero, invalid operations) and the generic errors they cause become a
:class:`~ionic_usd.errors.ParameterError` naming the parameter, and the result is checked with
:func:`check_solid`.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TypeVar

import numpy as np

from ionic_usd.errors import BudgetError, GrammarError, IonicError, ParameterError
from ionic_usd.geometry.mesh import Mesh

__all__ = ["MAX_EXTENT", "check_solid", "guarded"]

#: |coordinate| limit of any generated part (m): a column part is not a kilometre long
MAX_EXTENT = 1000.0

T = TypeVar("T")


def solid_problem(mesh: Mesh) -> str | None:
    """Why ``mesh`` is not a closed, outward, finite solid — or None if it is."""
    if mesh.n_points == 0 or mesh.n_faces == 0:
        return "it has no faces"
    if not np.isfinite(mesh.points).all():
        return "it has non-finite points"
    ext = float(np.abs(mesh.points).max())
    if ext > MAX_EXTENT:
        return f"it reaches {ext:.3g} m from the origin (limit {MAX_EXTENT:g} m)"
    for name in ("normals", "st"):
        cv = getattr(mesh, name, None)
        arr = None if cv is None else cv.values
        if arr is not None and not np.isfinite(np.asarray(arr)).all():
            return f"its {name} are not finite (degenerate faces)"
    tri = mesh.triangles
    n = np.int64(mesh.n_points)
    a = tri.astype(np.int64)
    b = np.roll(a, -1, axis=1)
    fwd = np.sort((a * n + b).ravel())  # directed edges as one int64 key each
    rev = np.sort((b * n + a).ravel())
    repeated = int(np.count_nonzero(fwd[1:] == fwd[:-1]))
    if repeated:
        return f"its faces are not consistently wound or not manifold ({repeated} edges)"
    if not np.array_equal(fwd, rev):  # every edge must meet its reverse exactly once
        return f"it is not closed ({int(np.count_nonzero(fwd != rev))} open edges)"
    p = mesh.points
    v = float(np.einsum("ij,ij->i", p[tri[:, 0]], np.cross(p[tri[:, 1]], p[tri[:, 2]])).sum() / 6.0)
    diag = float(np.linalg.norm(np.ptp(p, axis=0)))
    if not v > 1e-9 * diag**3:  # a flat (zero-volume) solid is as wrong as an inverted one
        return f"it is inside out or flat (volume {v:.3g} m³)"
    return None


def check_solid(mesh: Mesh, param: str, value: object, *, context: str = "") -> Mesh:
    """Return ``mesh`` if it is a closed, outward, finite solid, else raise
    :class:`ParameterError` naming ``param`` = ``value``."""
    why = solid_problem(mesh)
    if why is not None:
        raise ParameterError(
            param,
            _short(value),
            f"a shape that builds a closed, outward solid ({mesh.name}: {why})",
            context=context,
        )
    return mesh


def _short(value: object) -> object:
    if isinstance(value, str) and len(value) > 80:
        return value[:77] + "..."
    return value


def guarded(
    build: Callable[[], T],
    param: str,
    value: object,
    *,
    context: str = "",
    check: Callable[[T], list[Mesh]] | None = None,
) -> T:
    """Run ``build()`` with floating-point faults raised, converting any non-package error to
    a :class:`ParameterError` naming ``param``; then check every mesh ``check(result)``
    returns (default: the result itself if it is a Mesh) with :func:`check_solid`."""
    try:
        with np.errstate(over="raise", divide="raise", invalid="raise"):
            result = build()
    except (ParameterError, GrammarError, BudgetError):
        raise
    except (IonicError, ArithmeticError, ValueError, IndexError) as exc:  # GeometryError too
        msg = " ".join(str(exc).split())[:120] or type(exc).__name__
        raise ParameterError(
            param,
            _short(value),
            f"a shape that can be built (it fails with {type(exc).__name__}: {msg})",
            context=context,
        ) from None
    if check is not None:
        meshes = check(result)
    else:
        meshes = [result] if isinstance(result, Mesh) else []
    for m in meshes:
        check_solid(m, param, value, context=context)
    return result
