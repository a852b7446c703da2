"""USD for scan fits: the scan as ``UsdGeom.Points`` with its deviation, and the fitted column
placed in the scan's frame."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from pxr import Gf, Sdf, Vt

from ionic_usd.geometry.mesh import Mesh
from ionic_usd.usd.mesh import author_attribute, author_mesh, define_prim
from ionic_usd.usd.stage import check_output_path, new_layer, save_layer

__all__ = ["ColonnadeInstance", "write_colonnade", "write_fitted_column", "write_scan_points"]

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


@dataclass(frozen=True)
class ColonnadeInstance:
    """One column of a fitted colonnade: its group's name, its pose and what differs.

    matrix : (4, 4) ``p_scan = [p_column, 1] @ matrix`` (the column's pose, its turn included)
    shaft_turn : degrees about the column's axis (+Y) that turn the group's shaft to this
        column's flute phase (the base and capital keep the column's turn)
    deviation : rms, p95, max (m) of the column's points from the group's description
    """

    group: str
    matrix: np.ndarray
    shaft_turn: float
    deviation: Mapping[str, float]


def _matrix(m: np.ndarray) -> Gf.Matrix4d:
    return Gf.Matrix4d(*[float(v) for v in np.asarray(m, dtype=np.float64).ravel()])


def write_colonnade(
    path: str | Path,
    prototypes: Mapping[str, Mapping[str, Mesh]],
    instances: Sequence[ColonnadeInstance],
    *,
    comment: str = "",
    force: bool = False,
) -> Path:
    """A fitted colonnade as instances of one column per group.

    Each group's parts (``Base``, ``Shaft``, ``CapitalBody``: column coordinates, y up) are
    authored once, under the class prim ``/_Column_<group>`` (``<part>/Mesh``). Each column
    is ``/Colonnade/Column_<k>`` (kind ``component``, ``xformOp:transform`` = its pose) whose
    parts are instanceable references to the group's, so a renderer holds one copy of each
    part per group; the shaft's reference is turned by ``shaft_turn`` about the axis (the
    column's flute phase). The column's deviation from its group's description is on it, in
    ``customData["ionic_usd"]["fit"]`` and as ``userProperties:fit:*`` (DCCs show those).
    """
    check_output_path(path, force=force)
    layer = new_layer("Colonnade", kind="assembly", comment=comment)
    with Sdf.ChangeBlock():
        for g, parts in prototypes.items():
            cls = Sdf.CreatePrimInLayer(layer, f"/_Column_{g}")
            cls.specifier = Sdf.SpecifierClass
            for name, mesh in parts.items():
                define_prim(layer, f"/_Column_{g}/{name}", "Xform")
                author_mesh(layer, f"/_Column_{g}/{name}/Mesh", mesh)
        for k, inst in enumerate(instances, start=1):
            col = define_prim(layer, f"/Colonnade/Column_{k}", "Xform")
            col.kind = "component"
            author_attribute(col, "xformOp:transform", _T.Matrix4d, _matrix(inst.matrix))
            author_attribute(
                col,
                "xformOpOrder",
                _T.TokenArray,
                Vt.TokenArray(["xformOp:transform"]),
                uniform=True,
            )
            dev = {key: float(v) for key, v in inst.deviation.items()}
            col.customData = {"ionic_usd": {"fit": {"group": inst.group, **dev}}}
            author_attribute(col, "userProperties:fit:group", _T.String, inst.group)
            for key, v in dev.items():
                author_attribute(col, f"userProperties:fit:deviation_{key}_m", _T.Double, v)
            for name in prototypes[inst.group]:
                part = define_prim(layer, f"/Colonnade/Column_{k}/{name}", "Xform")
                part.referenceList.Prepend(Sdf.Reference(primPath=f"/_Column_{inst.group}/{name}"))
                part.instanceable = True
                if name == "Shaft" and inst.shaft_turn:
                    author_attribute(part, "xformOp:rotateY", _T.Double, float(inst.shaft_turn))
                    author_attribute(
                        part,
                        "xformOpOrder",
                        _T.TokenArray,
                        Vt.TokenArray(["xformOp:rotateY"]),
                        uniform=True,
                    )
    return save_layer(layer, path, force=force)
