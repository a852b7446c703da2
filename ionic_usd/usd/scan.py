"""USD for scan fits: the scan as ``UsdGeom.Points`` with its deviation, and the fitted column
placed in the scan's frame."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from pxr import Gf, Sdf, Vt

from ionic_usd.geometry.mesh import Mesh
from ionic_usd.usd.mesh import author_attribute, author_mesh, define_prim
from ionic_usd.usd.stage import check_output_path, new_layer, save_layer

__all__ = ["write_scan_points", "write_fitted_column"]

_T = Sdf.ValueTypeNames


def write_scan_points(
    path: str | Path,
    points: np.ndarray,
    deviation: np.ndarray,
    colours: np.ndarray,
    *,
    width: float,
    force: bool = False,
) -> Path:
    """``/Scan/Points`` (``UsdGeom.Points``) with ``primvars:deviation`` (metres, vertex) and
    a heat-map ``primvars:displayColor`` (vertex).

    Parameters
    ----------
    points : (n, 3) float, metres
    deviation : (n,) float, metres, finite
    colours : (n, 3) float in [0, 1]
    width : point width (m)
    """
    check_output_path(path, force=force)
    pts = np.ascontiguousarray(points, dtype=np.float32)
    layer = new_layer("Scan", kind="component", comment="ionic_usd scan with deviations")
    with Sdf.ChangeBlock():
        spec = define_prim(layer, "/Scan/Points", "Points")
        author_attribute(spec, "points", _T.Point3fArray, Vt.Vec3fArray.FromNumpy(pts))
        lo, hi = pts.min(axis=0), pts.max(axis=0)
        author_attribute(
            spec,
            "extent",
            _T.Float3Array,
            Vt.Vec3fArray([Gf.Vec3f(*map(float, lo)), Gf.Vec3f(*map(float, hi))]),
        )
        author_attribute(
            spec, "widths", _T.FloatArray, Vt.FloatArray([float(width)]), interpolation="constant"
        )
        author_attribute(
            spec,
            "primvars:deviation",
            _T.FloatArray,
            Vt.FloatArray.FromNumpy(np.ascontiguousarray(deviation, dtype=np.float32)),
            interpolation="vertex",
        )
        author_attribute(
            spec,
            "primvars:displayColor",
            _T.Color3fArray,
            Vt.Vec3fArray.FromNumpy(np.ascontiguousarray(colours, dtype=np.float32)),
            interpolation="vertex",
        )
    return save_layer(layer, path, force=force)


def write_fitted_column(
    path: str | Path,
    meshes: dict[str, Mesh],
    matrix: np.ndarray,
    *,
    comment: str = "",
    force: bool = False,
) -> Path:
    """The fitted column's meshes under ``/Column/Geom`` with ``/Column`` transformed by
    ``matrix`` (column coordinates → the scan's frame; row-vector convention as USD).

    Parameters
    ----------
    matrix : (4, 4) float, ``p_scan = [p_column, 1] @ matrix``
    """
    check_output_path(path, force=force)
    layer = new_layer("Column", kind="component", comment=comment)
    with Sdf.ChangeBlock():
        root = layer.GetPrimAtPath("/Column")
        m = Gf.Matrix4d(*[float(v) for v in np.asarray(matrix, dtype=np.float64).ravel()])
        author_attribute(root, "xformOp:transform", _T.Matrix4d, m)
        author_attribute(
            root, "xformOpOrder", _T.TokenArray, Vt.TokenArray(["xformOp:transform"]), uniform=True
        )
        define_prim(layer, "/Column/Geom", "Xform")
        for name, mesh in meshes.items():
            author_mesh(layer, f"/Column/Geom/{name}", mesh)
    return save_layer(layer, path, force=force)
