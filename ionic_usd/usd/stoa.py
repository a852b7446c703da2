"""The stoas' and the ground's USD: a stoa asset of instanced parts, and the paved ground.

``Stoas/Stoa.usda`` (text, small): ``/Stoa`` (assembly) holding one component per part
prototype — ``Bay`` (the unit bay of :func:`ionic_usd.city.stoa.bay_parts`) and
``Corner_<k>`` (one per distinct corner turn) — each with its meshes and its own materials
(stucco walls and entablature, terracotta roof: the temple builds' maps). The city places
them with one PointInstancer, ``/City/Stoas`` (kind = group): the bays scaled along their
run to their length (``scales = (length, 1, 1)``), the corners as they are.

``Ground.usda``: ``/Ground`` (component) with the meshes of :mod:`ionic_usd.city.ground`
(paving in travertine, plazas in stucco-white stone, lots in terracotta-tinted stone: each a
material reading a temple build's maps), referenced by ``/City/Ground``.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from pxr import Gf, Sdf, Vt

from ionic_usd.city.layout import yaw_quaternions
from ionic_usd.city.stoa import StoaDims, bay_parts, corner_parts
from ionic_usd.geometry.mesh import CornerValues, Mesh, box_st, face_normals, triangulate_fan
from ionic_usd.usd.materials import (
    TILE_METRES,
    MaterialTextures,
    author_preview_material,
    bind_material_spec,
)
from ionic_usd.usd.mesh import author_mesh, define_prim
from ionic_usd.usd.stage import create_stage, save_layer

__all__ = ["StoaInstances", "author_ground", "author_stoa_instancer", "write_ground", "write_stoa"]

_T = Sdf.ValueTypeNames
_ROOF = ("Roof", "CornerRoof")


@dataclass(frozen=True)
class StoaInstances:
    """Stoa parts to place: prototype index (0 = Bay, 1 + k = Corner_k), USD x, z, yaw
    (degrees), length along local X (1 for corners)."""

    proto: np.ndarray
    xz: np.ndarray
    yaw: np.ndarray
    length: np.ndarray

    def __len__(self) -> int:
        return len(self.proto)


def _textured(mesh: Mesh, x_scale: float = 1.0) -> Mesh:
    """``mesh`` with flat per-corner normals and box-mapped ``st`` (one repeat per
    :data:`TILE_METRES`; local X stretched by ``x_scale``, the bay's nominal length)."""
    counts = mesh.face_vertex_counts
    tri = triangulate_fan(counts, mesh.face_vertex_indices)
    n_tri, _ = face_normals(mesh.points, tri)
    first = np.concatenate([[0], np.cumsum(counts - 2)[:-1]])  # each face's first triangle
    normals = np.repeat(n_tri[first], counts, axis=0).astype(np.float32)
    corners = mesh.points[mesh.face_vertex_indices] * [x_scale, 1.0, 1.0]
    st = (box_st(corners, normals) / TILE_METRES).astype(np.float32)
    k = len(mesh.face_vertex_indices)
    return mesh.with_(
        normals=CornerValues.per_corner(normals),
        st=CornerValues(st, np.arange(k, dtype=np.int32)),
    )


def _materials(stage, root: str, maps: Mapping[str, str]) -> dict[str, str]:
    """One preview material per map set under ``root``/Materials; returns name → path."""
    out = {}
    for name, stem in maps.items():
        path = f"{root}/Materials/{name}"
        author_preview_material(
            stage,
            path,
            MaterialTextures(*(f"{stem}_{r}.png" for r in ("basecolor", "roughness", "normal"))),
        )
        out[name] = path
    return out


def write_stoa(
    path: Path,
    dims: StoaDims,
    corners: Sequence[np.ndarray],
    maps: Mapping[str, str],
    spacing: float,
) -> list[tuple[np.ndarray, np.ndarray, int]]:
    """Write the stoa asset (see the module docstring); ``corners``: each corner prototype's
    second back normal (local X, Z); ``maps``: ``Stucco`` and ``Roof`` → texture path stems
    relative to ``path``. Returns per prototype (Bay, Corner_0, …) its bounds and triangles."""
    stage = create_stage("Stoa", kind="assembly", comment="Stoa parts, placed by the city")
    layer = stage.GetRootLayer()
    stats = []
    parts = [("Bay", bay_parts(dims), spacing)]
    parts += [(f"Corner_{k}", corner_parts(dims, nb), 1.0) for k, nb in enumerate(corners)]
    for name, meshes, xs in parts:
        root = f"/Stoa/{name}"
        spec = define_prim(layer, root, "Xform")
        spec.kind = "component"
        mats = _materials(stage, root, maps)
        pts = []
        tris = 0
        for m in meshes:
            mesh_spec = author_mesh(layer, f"{root}/{m.name}", _textured(m, xs))
            bind_material_spec(mesh_spec, mats["Roof" if m.name.startswith(_ROOF) else "Stucco"])
            pts.append(m.points)
            tris += int(np.sum(m.face_vertex_counts - 2))
        allp = np.concatenate(pts)
        stats.append((allp.min(axis=0), allp.max(axis=0), tris))
    save_layer(layer, path, force=True)
    return stats


def author_stoa_instancer(
    layer: Sdf.Layer,
    path: str,
    asset: str,
    names: Sequence[str],
    inst: StoaInstances,
    bounds: Sequence[tuple[np.ndarray, np.ndarray]],
) -> tuple[np.ndarray, np.ndarray]:
    """A PointInstancer (kind = group) of the stoa's parts; returns its extent (lo, hi)."""
    pi = define_prim(layer, path, "PointInstancer")
    pi.kind = "group"
    protos = define_prim(layer, f"{path}/Prototypes", "Scope")
    protos.kind = "group"
    targets = []
    for name in names:
        spec = define_prim(layer, f"{path}/Prototypes/{name}", "Xform")
        spec.payloadList.Prepend(Sdf.Payload(asset, Sdf.Path(f"/Stoa/{name}")))  # loads on demand
        targets.append(spec.path)
    Sdf.RelationshipSpec(pi, "prototypes", custom=False).targetPathList.explicitItems = targets
    n = len(inst)
    pos = np.zeros((n, 3), dtype=np.float32)
    pos[:, 0], pos[:, 2] = inst.xz[:, 0], inst.xz[:, 1]
    Sdf.AttributeSpec(pi, "positions", _T.Point3fArray).default = Vt.Vec3fArray.FromNumpy(pos)
    Sdf.AttributeSpec(pi, "protoIndices", _T.IntArray).default = Vt.IntArray.FromNumpy(
        np.ascontiguousarray(inst.proto, dtype=np.int32)
    )
    Sdf.AttributeSpec(pi, "orientations", _T.QuathArray).default = Vt.QuathArray.FromNumpy(
        yaw_quaternions(inst.yaw)
    )
    scale = np.ones((n, 3), dtype=np.float32)
    scale[:, 0] = inst.length
    Sdf.AttributeSpec(pi, "scales", _T.Float3Array).default = Vt.Vec3fArray.FromNumpy(scale)
    lo, hi = placed_bounds(inst, bounds)
    Sdf.AttributeSpec(pi, "extent", _T.Float3Array).default = Vt.Vec3fArray(
        [Gf.Vec3f(*map(float, lo)), Gf.Vec3f(*map(float, hi))]
    )
    return lo, hi


def placed_bounds(
    inst: StoaInstances, bounds: Sequence[tuple[np.ndarray, np.ndarray]]
) -> tuple[np.ndarray, np.ndarray]:
    """Exact axis-aligned bounds of the placed prototype boxes (scaled along X, turned)."""
    if not len(inst):
        return np.zeros(3), np.zeros(3)
    lo = np.array([b[0] for b in bounds])[inst.proto]
    hi = np.array([b[1] for b in bounds])[inst.proto]
    a = np.radians(inst.yaw)
    c, s = np.cos(a), np.sin(a)
    xs = np.stack([lo[:, 0], hi[:, 0]], axis=1) * inst.length[:, None]
    zs = np.stack([lo[:, 2], hi[:, 2]], axis=1)
    wx = xs[:, :, None] * c[:, None, None] + zs[:, None, :] * s[:, None, None]
    wz = -xs[:, :, None] * s[:, None, None] + zs[:, None, :] * c[:, None, None]
    wx = wx.reshape(len(a), -1) + inst.xz[:, :1]
    wz = wz.reshape(len(a), -1) + inst.xz[:, 1:]
    return (
        np.array([wx.min(), lo[:, 1].min(), wz.min()]),
        np.array([wx.max(), hi[:, 1].max(), wz.max()]),
    )


def write_ground(path: Path, meshes: Sequence[Mesh], maps: Mapping[str, str]) -> int:
    """Write ``Ground.usda`` (see the module docstring); ``maps``: mesh name → texture path
    stem relative to ``path``. Returns its triangles."""
    stage = create_stage("Ground", kind="component", comment="The city's paving and lots")
    layer = stage.GetRootLayer()
    mats = _materials(stage, "/Ground", maps)
    tris = 0
    for m in meshes:
        spec = author_mesh(layer, f"/Ground/{m.name}", m)
        bind_material_spec(spec, mats[m.name])
        tris += int(np.sum(m.face_vertex_counts - 2))
    save_layer(layer, path, force=True)
    return tris


def author_ground(layer: Sdf.Layer, path: str, asset: str) -> None:
    """``path`` (a component) with the ground layer ``asset`` as its payload (a city opened
    with LoadNone composes no mesh)."""
    spec = define_prim(layer, path, "Xform")
    spec.payloadList.Prepend(Sdf.Payload(asset))
