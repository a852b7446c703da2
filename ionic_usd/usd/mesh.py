"""Author :class:`ionic_usd.geometry.Mesh` values as ``UsdGeom.Mesh`` prims with the Sdf API.

Arrays go straight from numpy to USD (``Vt.*Array.FromNumpy``); callers that author many prims
wrap the calls in one ``Sdf.ChangeBlock`` so change processing runs once.
"""

from __future__ import annotations

import numpy as np
from pxr import Sdf, Vt

from ionic_usd.geometry.indexing import distinct_values
from ionic_usd.geometry.mesh import Mesh
from ionic_usd.usd.stage import ensure_typed_ancestors

__all__ = [
    "author_attribute",
    "author_mesh",
    "define_prim",
    "mesh_extent",
    "write_meshes",
]

_T = Sdf.ValueTypeNames


def define_prim(layer: Sdf.Layer, path: str | Sdf.Path, type_name: str = "Xform") -> Sdf.PrimSpec:
    """A ``def`` prim spec of a type, with typed ancestors."""
    path = Sdf.Path(str(path))
    ensure_typed_ancestors(layer, path)
    spec = layer.GetPrimAtPath(path) or Sdf.CreatePrimInLayer(layer, path)
    spec.specifier = Sdf.SpecifierDef
    spec.typeName = type_name
    return spec


def author_attribute(
    spec: Sdf.PrimSpec,
    name: str,
    type_name,
    value,
    *,
    uniform: bool = False,
    interpolation: str | None = None,
) -> Sdf.AttributeSpec:
    """Set an attribute's default value, creating the attribute spec when it is missing.

    ``uniform`` makes a new attribute uniform (an existing one keeps its variability);
    ``interpolation``, when given, sets the primvar interpolation metadata.
    """
    attr = spec.attributes.get(name)
    if attr is None:
        variability = Sdf.VariabilityUniform if uniform else Sdf.VariabilityVarying
        attr = Sdf.AttributeSpec(spec, name, type_name, variability)
    attr.default = value
    if interpolation is not None:
        attr.SetInfo("interpolation", interpolation)
    return attr


def mesh_extent(mesh: Mesh) -> Vt.Vec3fArray:
    """The mesh's bounds as a USD ``extent`` value."""
    return _floats(Vt.Vec3fArray, mesh.extent)


# Vt.*Array.FromNumpy converts element by element through the buffer protocol, walking an
# n-dimensional index: a flat float32 view of an (n, 3) array converts in about half the time
# (measured at 0.63 M points: 9.1 -> 5.2 ms), the same values (FromNumpy groups the flat
# items by the element's width)
def _floats(cls, a: np.ndarray):
    return cls.FromNumpy(np.ascontiguousarray(a, dtype=np.float32).reshape(-1))


def _ints(a: np.ndarray) -> Vt.IntArray:
    return Vt.IntArray.FromNumpy(np.ascontiguousarray(a, dtype=np.int32).reshape(-1))


def _counts(counts: np.ndarray) -> Vt.IntArray:
    """``faceVertexCounts``; all equal (a triangle mesh) as a filled array, not a conversion."""
    if counts.size and counts.min() == counts.max():
        return Vt.IntArray(int(counts.size), int(counts[0]))
    return _ints(counts)


def author_mesh(
    layer: Sdf.Layer,
    path: str | Sdf.Path,
    mesh: Mesh,
    *,
    double_sided: bool = False,
) -> Sdf.PrimSpec:
    """Write a mesh prim (points, counts, indices, normals, st, extent, no subdivision).

    Parameters
    ----------
    layer : the layer to author into
    path : prim path; missing ancestors are created as ``Xform``
    mesh : the geometry; normals and ``st`` are written when present, their encoding chosen
        here: point normals (``normals.by_point``) as the ``normals`` attribute with vertex
        interpolation, per-corner ones as the indexed faceVarying primvar
        ``primvars:normals``, its values made distinct and all used by
        :func:`~ionic_usd.geometry.indexing.distinct_values`; ``st`` as the indexed
        faceVarying primvar ``primvars:st``, de-duplicated the same way unless
        ``st.distinct`` says the producer indexed it already)
    """
    spec = define_prim(layer, path, "Mesh")
    author_attribute(spec, "points", _T.Point3fArray, _floats(Vt.Vec3fArray, mesh.points))
    author_attribute(spec, "faceVertexCounts", _T.IntArray, _counts(mesh.face_vertex_counts))
    author_attribute(spec, "faceVertexIndices", _T.IntArray, _ints(mesh.face_vertex_indices))
    author_attribute(spec, "extent", _T.Float3Array, mesh_extent(mesh))
    author_attribute(spec, "subdivisionScheme", _T.Token, "none", uniform=True)
    author_attribute(spec, "doubleSided", _T.Bool, bool(double_sided), uniform=True)
    if mesh.normals is not None:
        nrm = mesh.normals
        if nrm.by_point:
            author_attribute(
                spec,
                "normals",
                _T.Normal3fArray,
                _floats(Vt.Vec3fArray, nrm.values),
                interpolation="vertex",
            )
        else:
            # faceVarying normals as an indexed primvar, each distinct value once and every
            # value used (NVIDIA's IndexedPrimvar and UnusedPrimvar rules). Only a primvar can
            # be indexed; UsdGeomPointBased: "if 'normals' and 'primvars:normals' are both
            # specified, the latter has precedence" (Hydra, Blender and usdview read the
            # primvar first), so exactly one of the two is authored
            values, indices = distinct_values(
                nrm.values, None if nrm.one_per_corner else nrm.indices
            )
            _indexed_primvar(spec, "normals", _T.Normal3fArray, Vt.Vec3fArray, values, indices)
    if mesh.st is not None:
        sti = mesh.st.corner_indices(mesh.face_vertex_indices)
        if mesh.st.distinct:
            st, st_indices = mesh.st.values, sti  # the generator's own indexing: as it is
        else:
            st, st_indices = distinct_values(mesh.st.values, sti)
        _indexed_primvar(spec, "st", _T.TexCoord2fArray, Vt.Vec2fArray, st, st_indices)
    return spec


def _indexed_primvar(
    spec: Sdf.PrimSpec, name: str, type_name, vt_cls, values: np.ndarray, indices: np.ndarray
) -> None:
    """A faceVarying indexed primvar ``primvars:<name>`` with its ``:indices``."""
    author_attribute(
        spec, f"primvars:{name}", type_name, _floats(vt_cls, values), interpolation="faceVarying"
    )
    author_attribute(spec, f"primvars:{name}:indices", _T.IntArray, _ints(indices))


def write_meshes(
    path,
    meshes: dict[str, Mesh],
    *,
    root: str = "Column",
    kind: str = "component",
    force: bool = False,
    comment: str = "",
):
    """Write meshes as ``/<root>/Geom/<name>`` into a new USD file (atomically).

    Returns the written path. Every ancestor is a typed ``Xform``; the root has ``kind``.
    """
    from ionic_usd.usd.stage import check_output_path, new_layer, save_layer  # noqa: PLC0415

    check_output_path(path, force=force)
    layer = new_layer(root, kind=kind, comment=comment)
    with Sdf.ChangeBlock():
        define_prim(layer, f"/{root}/Geom", "Scope")
        for name, mesh in meshes.items():
            author_mesh(layer, f"/{root}/Geom/{name}", mesh)
    return save_layer(layer, path, force=force)
