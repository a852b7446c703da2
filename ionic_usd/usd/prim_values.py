"""Prim values read as plain data: a ``UsdGeom.Mesh``'s arrays, paradata as JSON, content keys.

:func:`read_mesh_arrays` turns one mesh prim into numpy arrays with every primvar expanded to
one value per face corner where it is not per vertex, points and lines dropped, and a
left-handed mesh's winding reversed (so faces are counter-clockwise seen from outside).
:func:`to_json_value` and :func:`prim_paradata` turn ``customData`` and ``userProperties:*``
into JSON-ready values. The scene walk that uses them is :mod:`ionic_usd.usd.reader`.
"""

from __future__ import annotations

import hashlib
from collections.abc import Mapping, Sequence
from typing import NamedTuple

import numpy as np
from pxr import Sdf, Usd, UsdGeom

from ionic_usd.errors import GeometryError

__all__ = [
    "MeshArrays",
    "as_array",
    "content_key",
    "display_colour",
    "merge_paradata",
    "prim_paradata",
    "read_mesh_arrays",
    "to_json_value",
]


class MeshArrays(NamedTuple):
    """A mesh prim's values: points (n, 3), face_vertex_counts (f,), face_vertex_indices (k,),
    normals ((n, 3) 'vertex' or (k, 3) 'faceVarying', or None), normals_interpolation,
    st ((k, 2) per corner, or None), double_sided."""

    points: np.ndarray
    face_vertex_counts: np.ndarray
    face_vertex_indices: np.ndarray
    normals: np.ndarray | None
    normals_interpolation: str
    st: np.ndarray | None
    double_sided: bool


# -- JSON paradata -----------------------------------------------------------------------------
def to_json_value(v: object) -> object:
    """A USD value (dictionary, Vt array, Gf vector, asset path…) as plain JSON data."""
    if isinstance(v, Mapping):
        return {str(k): to_json_value(x) for k, x in v.items()}
    if isinstance(v, (bool, int, str)) or v is None:
        return v
    if isinstance(v, float):
        return v if np.isfinite(v) else None
    if isinstance(v, Sdf.AssetPath):
        return v.path
    if isinstance(v, Sdf.Path):
        return str(v)
    if isinstance(v, (list, tuple)) or hasattr(v, "__len__") and not isinstance(v, bytes):
        try:
            return [to_json_value(x) for x in v]  # type: ignore[attr-defined]
        except TypeError:
            pass
    if isinstance(v, (np.integer, np.floating)):
        return to_json_value(v.item())
    return str(v)


def prim_paradata(prim: Usd.Prim) -> dict:
    """A prim's ``customData`` and ``userProperties:*`` attributes as JSON-ready values."""
    out: dict = {}
    cd = prim.GetAllAuthoredMetadata().get("customData")  # not the schemas' userDocBrief
    if cd:
        out.update(to_json_value(dict(cd)))  # type: ignore[call-overload]
    props = {}
    for attr in prim.GetAuthoredAttributes():
        name = attr.GetName()
        if name.startswith("userProperties:"):
            props[name.split(":", 1)[1]] = to_json_value(attr.Get())
    if props:
        out["userProperties"] = props
    return out


def merge_paradata(outer: dict, inner: dict) -> dict:
    """``outer`` updated by ``inner``, nested dictionaries merged key by key."""
    out = dict(outer)
    for k, v in inner.items():
        nested = isinstance(v, dict) and isinstance(out.get(k), dict)
        out[k] = merge_paradata(out[k], v) if nested else v
    return out


# -- meshes ------------------------------------------------------------------------------------
def as_array(value, dtype) -> np.ndarray:
    """A USD array value (or None: empty) as a numpy array of ``dtype``."""
    return np.asarray(value if value is not None else [], dtype=dtype)


def _corner_values(
    pv: UsdGeom.Primvar, n_points: int, counts: np.ndarray, idx: np.ndarray, width: int, what: str
) -> np.ndarray | None:
    """A primvar (indexed or not) expanded to one value per face corner: (k, width)."""
    if not pv or not pv.HasValue():
        return None
    vals = as_array(pv.ComputeFlattened(), np.float64).reshape(-1, width)
    interp = pv.GetInterpolation()
    if interp == UsdGeom.Tokens.faceVarying and len(vals) == len(idx):
        return vals
    if interp in (UsdGeom.Tokens.vertex, UsdGeom.Tokens.varying) and len(vals) == n_points:
        return vals[idx]
    if interp == UsdGeom.Tokens.uniform and len(vals) == len(counts):
        return np.repeat(vals, counts, axis=0)
    if interp == UsdGeom.Tokens.constant and len(vals) >= 1:
        return np.repeat(vals[:1], len(idx), axis=0)
    raise GeometryError(
        f"{pv.GetAttr().GetPath()}: {len(vals)} {what} values do not fit interpolation {interp}"
    )


def read_mesh_arrays(prim: Usd.Prim, t: Usd.TimeCode) -> MeshArrays | None:
    """A mesh prim's values at ``t``, or None when it has no face with area.

    Raises GeometryError for indices that do not match the points, non-finite values, or a
    primvar whose length does not fit its interpolation.
    """
    mesh = UsdGeom.Mesh(prim)
    pts = as_array(mesh.GetPointsAttr().Get(t), np.float64).reshape(-1, 3)
    counts = as_array(mesh.GetFaceVertexCountsAttr().Get(t), np.int64)
    idx = as_array(mesh.GetFaceVertexIndicesAttr().Get(t), np.int64)
    if len(pts) == 0 or len(counts) == 0:
        return None
    if counts.sum() != len(idx) or (len(idx) and (idx.min() < 0 or idx.max() >= len(pts))):
        raise GeometryError(
            f"{prim.GetPath()}: faceVertexCounts/faceVertexIndices do not match {len(pts)} points"
        )
    if not np.all(np.isfinite(pts)):
        raise GeometryError(f"{prim.GetPath()}: points contain non-finite values")
    keep = counts >= 3  # points and lines carry no area
    if not keep.all():
        corner_keep = np.repeat(keep, counts)
        counts, idx = counts[keep], idx[corner_keep]
    else:
        corner_keep = None
    if len(counts) == 0:
        return None
    pvapi = UsdGeom.PrimvarsAPI(prim)
    nrm, interp = None, "vertex"
    pv = pvapi.GetPrimvar("normals")
    if pv and pv.HasValue():
        nrm = _corner_values(pv, len(pts), counts, idx, 3, "normal")
        interp = "faceVarying"
    elif mesh.GetNormalsAttr().HasValue():
        raw = as_array(mesh.GetNormalsAttr().Get(t), np.float64).reshape(-1, 3)
        ni = mesh.GetNormalsInterpolation()
        if ni in (UsdGeom.Tokens.vertex, UsdGeom.Tokens.varying) and len(raw) == len(pts):
            nrm = raw
        elif ni == UsdGeom.Tokens.faceVarying and corner_keep is not None:
            nrm, interp = raw[corner_keep], "faceVarying"
        elif ni == UsdGeom.Tokens.faceVarying and len(raw) == len(idx):
            nrm, interp = raw, "faceVarying"
        elif ni == UsdGeom.Tokens.uniform and len(raw) == len(keep):
            nrm, interp = np.repeat(raw[keep], counts, axis=0), "faceVarying"
        elif ni == UsdGeom.Tokens.constant and len(raw):
            nrm, interp = np.repeat(raw[:1], len(idx), axis=0), "faceVarying"
        else:
            raise GeometryError(
                f"{prim.GetPath()}: {len(raw)} normals do not fit interpolation {ni}"
            )
    st = None
    pv = pvapi.GetPrimvar("st")
    if pv and pv.HasValue() and corner_keep is None:
        st = _corner_values(pv, len(pts), counts, idx, 2, "st")
    for name, arr in (("normals", nrm), ("st", st)):
        if arr is not None and not np.all(np.isfinite(arr)):
            raise GeometryError(f"{prim.GetPath()}: {name} contain non-finite values")
    if mesh.GetOrientationAttr().Get() == UsdGeom.Tokens.leftHanded:
        # reverse each face's corners so the winding is counter-clockwise
        starts = np.concatenate([[0], np.cumsum(counts)[:-1]])
        order = np.concatenate(
            [s + np.arange(c)[::-1] for s, c in zip(starts, counts, strict=True)]
        )
        idx = idx[order]
        if st is not None:
            st = st[order]
        if nrm is not None and interp == "faceVarying":
            nrm = nrm[order]
    double = bool(mesh.GetDoubleSidedAttr().Get())
    return MeshArrays(pts, counts, idx, nrm, interp, st, double)


def content_key(arrays: Sequence[np.ndarray | None], extra: str) -> str:
    """A short hash of ``arrays`` (None allowed) and ``extra``: equal content, equal key."""
    h = hashlib.blake2b(digest_size=12)
    for a in arrays:
        h.update(b"-" if a is None else np.ascontiguousarray(a).tobytes())
        h.update(b"|")
    h.update(extra.encode())
    return h.hexdigest()


def display_colour(prim: Usd.Prim) -> tuple[float, float, float] | None:
    """The mean ``primvars:displayColor`` of a mesh (linear RGB), or None."""
    pv = UsdGeom.Mesh(prim).GetDisplayColorPrimvar()
    if pv and pv.HasValue():
        vals = as_array(pv.ComputeFlattened(), np.float64).reshape(-1, 3)
        if len(vals):
            r, g, b = (float(x) for x in vals.mean(axis=0))
            return (r, g, b)
    return None
