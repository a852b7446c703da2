"""Atlas values and packing: :class:`UVAtlas`, the common normalising size, analytic charts.

Consistent texel density between parts
--------------------------------------
A column is several meshes (base, shaft, capital, ...), each unwrapped on its own (one chart
set per part, so each can carry its own material and texture). :func:`apply_uvs` unwraps all
parts with the *same* density and then divides every part's pixel coordinates by one common
size ``S`` = the largest ``max(width, height)`` over all parts, rounded up to a power of two
(:func:`common_atlas_size`). Both axes are divided by the same ``S``, so texels stay square,
every ``st`` lies in [0, 1], and one texel of an ``S × S`` texture covers the same surface
area (``1 / texels_per_metre`` metres on a side) on every part: a tileable stone texture
looks equally fine on the 7 m shaft and on the small capital. If the resolution cap forced a
lower density on one part, all parts are unwrapped again at that lower density.
Alternative meshes that share a texture budget (variant sets: several bases for one LOD)
pass the same explicit ``atlas_size`` (compute it with :func:`common_atlas_size` over all
their atlases from :func:`unwrap_parts`).

Analytic charts
---------------
Surfaces of revolution and extrusions (the column base and shaft) have exact parametrisations:
their generators emit ``st`` in metres of surface (arc length along the profile or the height ×
arc length around), one chart per connected piece, seams split. :func:`analytic_atlas` turns
such metric charts into a :class:`UVAtlas` without xatlas: the charts (connected components of
the ``st`` indices) are scaled to ``texels_per_metre`` and shelf-packed with ``padding`` texels
between them, so they follow the same density and normalisation rules as xatlas atlases.
:func:`st_distortion` measures a parametrisation on the surface (anisotropy, area, winding).
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass, field

import numpy as np

from ionic_usd.errors import GeometryError, ParameterError
from ionic_usd.geometry.mesh import CornerValues, Mesh, chart_labels, frozen_array
from ionic_usd.lod import level

__all__ = [
    "DEFAULT_PADDING",
    "DEFAULT_RESOLUTION_CAP",
    "DEFAULT_TEXELS_PER_METRE",
    "UVAtlas",
    "analytic_atlas",
    "attach_uvs",
    "chart_labels",
    "check_atlas_size",
    "check_uv_options",
    "common_atlas_size",
    "next_pow2",
    "st_distortion",
]

#: the default texel density (px per metre of surface): the high level of detail's
#: ``atlas_texels_per_metre`` (:mod:`ionic_usd.lod`, where the other levels' are)
DEFAULT_TEXELS_PER_METRE: float = level("high").atlas_texels_per_metre
DEFAULT_PADDING = 4
DEFAULT_RESOLUTION_CAP = 8192


@dataclass(frozen=True, eq=False)
class UVAtlas:
    """Texture coordinates of one mesh in atlas pixels.

    Parameters
    ----------
    st_px : (u, 2) float32
        Chart vertex positions in pixels, ``0 <= x <= width``, ``0 <= y <= height``.
    st_indices : (k,) int32
        One index into ``st_px`` per face corner, in the order of ``face_vertex_indices``.
    width, height : int
        Atlas size in pixels.
    chart_count : int
    utilisation : float
        Fraction of the ``width × height`` atlas covered by charts (xatlas's estimate).
    texels_per_metre : float
        Density actually used (lower than requested only if the resolution cap forced it).
    seconds : float
        Wall time of the xatlas run(s) that produced the atlas; a diagnostic, not stored in
        the cache (0 for an atlas read from disk).
    st_distinct : bool
        Packed from a mesh whose ``st`` its generator indexed (a
        :class:`~ionic_usd.geometry.corners.CornerValues` with ``distinct``): each chart was
        moved and scaled as a whole, so the values stay one per chart vertex and
        :func:`attach_uvs` passes it on.
    """

    st_px: np.ndarray
    st_indices: np.ndarray
    width: int
    height: int
    chart_count: int
    utilisation: float
    texels_per_metre: float
    seconds: float = field(default=0.0, compare=False)
    st_distinct: bool = False

    def __post_init__(self) -> None:
        st = np.asarray(self.st_px, dtype=np.float32).reshape(-1, 2)
        sti = np.asarray(self.st_indices, dtype=np.int32).reshape(-1)
        for name in ("width", "height"):
            v = getattr(self, name)
            if int(v) != v or v < 1:
                raise ParameterError(name, v, "an integer >= 1", context="UVAtlas")
            object.__setattr__(self, name, int(v))
        if int(self.chart_count) != self.chart_count or self.chart_count < 0:
            raise ParameterError(
                "chart_count", self.chart_count, "an integer >= 0", context="UVAtlas"
            )
        object.__setattr__(self, "chart_count", int(self.chart_count))
        if not 0.0 <= float(self.utilisation) <= 1.0 + 1e-6:
            raise ParameterError(
                "utilisation", self.utilisation, "0 <= utilisation <= 1", context="UVAtlas"
            )
        if not (math.isfinite(self.texels_per_metre) and self.texels_per_metre > 0):
            raise ParameterError(
                "texels_per_metre", self.texels_per_metre, "a number > 0", context="UVAtlas"
            )
        if sti.size and (sti.min() < 0 or sti.max() >= len(st)):
            raise GeometryError("UVAtlas: st_indices out of range")
        if st.size and (
            not np.all(np.isfinite(st))
            or st.min() < -1e-3
            or np.any(st.max(axis=0) > np.array([self.width, self.height]) + 1e-3)
        ):
            raise GeometryError("UVAtlas: st_px outside the atlas")
        object.__setattr__(self, "st_px", frozen_array(st))
        object.__setattr__(self, "st_indices", frozen_array(sti))
        object.__setattr__(self, "utilisation", float(self.utilisation))
        object.__setattr__(self, "texels_per_metre", float(self.texels_per_metre))
        object.__setattr__(self, "st_distinct", bool(self.st_distinct))

    @property
    def size(self) -> int:
        """Longer side of the atlas in pixels."""
        return max(self.width, self.height)

    def st(self, atlas_size: int | None = None) -> np.ndarray:
        """(u, 2) float32 coordinates normalised by ``atlas_size`` on both axes.

        ``atlas_size`` defaults to :attr:`size` rounded up to a power of two and must be at
        least :attr:`size` so that the result lies in [0, 1].
        """
        s = next_pow2(self.size) if atlas_size is None else check_atlas_size(atlas_size)
        if s < self.size:
            raise ParameterError(
                "atlas_size", atlas_size, f"an integer >= {self.size} (this atlas's longer side)"
            )
        return (self.st_px.astype(np.float64) / s).astype(np.float32)


def next_pow2(n: int) -> int:
    return 1 << max(0, int(n) - 1).bit_length()


def check_atlas_size(atlas_size: int) -> int:
    if isinstance(atlas_size, bool) or int(atlas_size) != atlas_size or atlas_size < 1:
        raise ParameterError("atlas_size", atlas_size, "an integer >= 1")
    return int(atlas_size)


def check_uv_options(texels_per_metre: float, padding: int, resolution_cap: int) -> None:
    if (
        isinstance(texels_per_metre, bool)
        or not isinstance(texels_per_metre, int | float)
        or not math.isfinite(texels_per_metre)
        or texels_per_metre <= 0
    ):
        raise ParameterError(
            "texels_per_metre", texels_per_metre, "a finite number > 0", context="uv"
        )
    if isinstance(padding, bool) or int(padding) != padding or not 0 <= padding <= 64:
        raise ParameterError("padding", padding, "an integer 0..64", context="uv")
    if (
        isinstance(resolution_cap, bool)
        or int(resolution_cap) != resolution_cap
        or not 16 <= resolution_cap <= 65536
    ):
        raise ParameterError("resolution_cap", resolution_cap, "an integer 16..65536", context="uv")


def common_atlas_size(atlases: Iterable[UVAtlas]) -> int:
    """The normalising size S: the longest atlas side over all parts, rounded up to 2^n."""
    sides = [a.size for a in atlases]
    if not sides:
        raise GeometryError("common_atlas_size needs at least one atlas")
    return next_pow2(max(sides))


def attach_uvs(mesh: Mesh, atlas: UVAtlas, atlas_size: int | None = None) -> Mesh:
    """``mesh`` with ``st`` = ``atlas.st_px / atlas_size`` indexed by ``atlas.st_indices``.

    Points, faces and normals are untouched; ``st.distinct`` comes from the atlas.
    """
    if atlas.st_indices.size != mesh.face_vertex_indices.size:
        raise GeometryError(
            f"attach_uvs: atlas has {atlas.st_indices.size} corners, mesh {mesh.name!r} has "
            f"{mesh.face_vertex_indices.size}"
        )
    st = CornerValues(atlas.st(atlas_size), atlas.st_indices, atlas.st_distinct)
    return mesh.with_(st=st)


def analytic_atlas(
    mesh: Mesh,
    *,
    texels_per_metre: float = DEFAULT_TEXELS_PER_METRE,
    padding: int = DEFAULT_PADDING,
    resolution_cap: int = DEFAULT_RESOLUTION_CAP,
) -> UVAtlas:
    """Pack a mesh's own metric ``st`` charts into an atlas (no xatlas).

    Parameters
    ----------
    mesh : Mesh
        Triangles with ``st`` in metres of surface (an analytic parametrisation from the
        generator), indexed per corner so that the charts split at their seams.
    texels_per_metre, padding, resolution_cap : as for :func:`ionic_usd.texture.uv.unwrap`

    Returns
    -------
    UVAtlas whose charts keep their shape (translated only, never rotated or mirrored, so
    their winding and tangent frames stay as the generator made them), scaled to
    ``texels_per_metre`` and shelf-packed tallest first with ``padding`` texels around each.
    The atlas is derived data of the mesh: it is kept with the mesh's other derived values
    (a mesh computed in a worker process brings its atlas along to the process that packs).
    """
    check_uv_options(texels_per_metre, padding, resolution_cap)
    memo = ("analytic_atlas", float(texels_per_metre), int(padding), int(resolution_cap))
    if memo not in mesh._cache:
        mesh._cache[memo] = _analytic_atlas(mesh, texels_per_metre, padding, resolution_cap)
    return mesh._cache[memo]


def _analytic_atlas(
    mesh: Mesh, texels_per_metre: float, padding: int, resolution_cap: int
) -> UVAtlas:
    if mesh.st is None:
        raise GeometryError(f"analytic_atlas: mesh {mesh.name!r} has no st")
    if not np.all(mesh.face_vertex_counts == 3):
        raise GeometryError(f"analytic_atlas: mesh {mesh.name!r} has non-triangle faces")
    st = mesh.st.values.astype(np.float64)
    corner_st = mesh.st.corner_indices(mesh.face_vertex_indices)
    chart = chart_labels(corner_st, len(st))
    # every st value belongs to the chart of a triangle using it (values no corner uses
    # stay where they are and are clipped into the atlas)
    value_chart = np.zeros(len(st), dtype=np.int64)
    value_chart[corner_st.reshape(-1, 3)] = chart[:, None]
    n_charts = int(chart.max()) + 1 if chart.size else 0
    used = np.zeros(len(st), dtype=bool)
    used[corner_st] = True
    # chart boxes: sort the used values by chart, then one reduceat per bound
    order = np.flatnonzero(used)[np.argsort(value_chart[used], kind="stable")]
    starts = np.searchsorted(value_chart[order], np.arange(n_charts))
    lo = np.minimum.reduceat(st[order], starts, axis=0)
    hi = np.maximum.reduceat(st[order], starts, axis=0)
    tpm = float(texels_per_metre)
    area = float(np.prod(hi - lo, axis=1).sum())
    for _ in range(8):
        size_px = np.ceil((hi - lo) * tpm) + 2 * padding  # chart boxes with their gutters
        offset, width, height = _shelf_pack(size_px)
        if max(width, height) <= resolution_cap:
            break
        tpm *= 0.97 * resolution_cap / max(width, height)
    else:
        raise GeometryError(
            f"analytic_atlas: mesh {mesh.name!r} does not fit a {resolution_cap}² atlas"
        )
    px = (st - lo[value_chart]) * tpm + padding + offset[value_chart]
    px = np.clip(px, 0.0, [width, height])
    return UVAtlas(
        st_px=px.astype(np.float32),
        st_indices=corner_st,
        width=width,
        height=height,
        chart_count=n_charts,
        utilisation=min(1.0, area * tpm * tpm / (width * height)),
        texels_per_metre=tpm,
        st_distinct=mesh.st.distinct,
    )


def _shelf_pack(size: np.ndarray) -> tuple[np.ndarray, int, int]:
    """Place boxes (c, 2) on shelves, tallest first, rows no wider than a near-square side.

    Returns the lower-left corner of each box (c, 2) and the atlas width and height.
    """
    side = max(float(size[:, 0].max()), math.sqrt(float(np.prod(size, axis=1).sum())) * 1.1)
    offset = np.zeros_like(size)
    x = y = shelf = 0.0
    width = 0.0
    for i in np.argsort(-size[:, 1], kind="stable"):
        w, h = size[i]
        if x > 0 and x + w > side:
            x, y, shelf = 0.0, y + shelf, 0.0
        offset[i] = (x, y)
        x += w
        shelf = max(shelf, h)
        width = max(width, x)
    return offset, max(1, int(math.ceil(width))), max(1, int(math.ceil(y + shelf)))


def st_distortion(mesh: Mesh, min_area: float = 1e-12) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """How a triangle mesh's ``st`` maps its surface, triangle by triangle.

    Parameters
    ----------
    mesh : triangles with ``st``
    min_area : triangles with a smaller surface area (m²) are left out (their map is noise)

    Returns
    -------
    anisotropy : (k,) the ratio of the map's singular values (1: conformal; a square drawn on
        the surface stays a square in st), ``inf`` where st collapses the triangle to a line
    st_area : (k,) signed st area: negative where the chart winds against the face (folded)
    area : (k,) surface area of the same triangles
    """
    if mesh.st is None:
        raise GeometryError(f"st_distortion: mesh {mesh.name!r} has no st")
    p = mesh.points[mesh.triangles]
    s = mesh.st.at_corners(mesh.face_vertex_indices).reshape(-1, 3, 2).astype(np.float64)
    e1, e2 = p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]
    n = np.cross(e1, e2)
    area = np.linalg.norm(n, axis=1) / 2
    keep = area >= min_area
    e1, e2, n, s, area = e1[keep], e2[keep], n[keep], s[keep], area[keep]
    # each triangle in an orthonormal frame of its plane (x along its first edge)
    x = e1 / np.linalg.norm(e1, axis=1)[:, None]
    y = np.cross(n / np.linalg.norm(n, axis=1)[:, None], x)
    frame = np.stack(
        [
            np.stack([(e1 * x).sum(1), (e1 * y).sum(1)], 1),
            np.stack([(e2 * x).sum(1), (e2 * y).sum(1)], 1),
        ],
        2,
    )
    uv = np.stack([s[:, 1] - s[:, 0], s[:, 2] - s[:, 0]], 2)
    sv = np.linalg.svd(uv @ np.linalg.inv(frame), compute_uv=False)
    with np.errstate(divide="ignore"):
        anisotropy = sv[:, 0] / sv[:, 1]
    return anisotropy, np.linalg.det(uv) / 2, area
