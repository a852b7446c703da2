"""Tests for ionic_usd.texture.uv: xatlas unwrapping, common texel density, cache."""

from __future__ import annotations

import numpy as np
import pytest
from numpy.testing import assert_allclose, assert_array_equal
from scipy import ndimage
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from ionic_usd.errors import GeometryError, ParameterError
from ionic_usd.geometry.analysis import boundary_edges
from ionic_usd.geometry.curves import revolve
from ionic_usd.geometry.mesh import Mesh, face_normals, smooth_normals
from ionic_usd.texture.uv import (
    UVAtlas,
    UVCache,
    apply_uvs,
    attach_uvs,
    common_atlas_size,
    default_cache_folder,
    unwrap,
    unwrap_parts,
    uv_cache_key,
)

TPM = 32.0  # px/m: small atlases keep the tests fast


def cube(side: float, name: str = "cube") -> Mesh:
    """Closed cube [0, side]^3: 8 shared points, 12 outward triangles."""
    p = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], float) * side
    quads = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    tri = [[a, b, c] for a, b, c, d in quads] + [[a, c, d] for a, b, c, d in quads]
    return Mesh(p, np.full(12, 3), np.array(tri).reshape(-1), name=name)


def cylinder(radius: float = 0.5, height: float = 2.0, segments: int = 32) -> Mesh:
    prof = np.array([[0, 0], [radius, 0], [radius, height], [0, height]], float)
    return revolve(prof, segments, name="cylinder")[0]


def uv_areas(st: np.ndarray, st_indices: np.ndarray) -> np.ndarray:
    """(t,) signed areas of the UV triangles."""
    t = st.astype(np.float64)[st_indices.reshape(-1, 3)]
    e1, e2 = t[:, 1] - t[:, 0], t[:, 2] - t[:, 0]
    return 0.5 * (e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])


def uv_charts(st_indices: np.ndarray, n_st: int) -> np.ndarray:
    """(t,) chart label per triangle: connected components of the shared UV vertices."""
    tri = st_indices.reshape(-1, 3)
    rows = np.concatenate([tri[:, 0], tri[:, 1]])
    cols = np.concatenate([tri[:, 1], tri[:, 2]])
    g = coo_matrix((np.ones(rows.size), (rows, cols)), shape=(n_st, n_st))
    return connected_components(g, directed=False)[1][tri[:, 0]]


def rasterise(
    st_px: np.ndarray, st_indices: np.ndarray, width: int, height: int, labels: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Count triangles covering each pixel centre (strictly inside) and record a label.

    Returns (coverage (h, w) int, label (h, w) int with -1 where empty).
    """
    cover = np.zeros((height, width), dtype=np.int32)
    label = np.full((height, width), -1, dtype=np.int64)
    tris = st_px.astype(np.float64)[st_indices.reshape(-1, 3)]
    for t, lab in zip(tris, labels, strict=True):
        a, b, c = t
        det = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
        if abs(det) < 1e-12:
            continue
        x0, y0 = np.floor(t.min(axis=0)).astype(int)
        x1, y1 = np.ceil(t.max(axis=0)).astype(int)
        xs, ys = np.meshgrid(
            np.arange(max(x0, 0), min(x1, width)) + 0.5,
            np.arange(max(y0, 0), min(y1, height)) + 0.5,
        )
        l1 = ((xs - a[0]) * (c[1] - a[1]) - (ys - a[1]) * (c[0] - a[0])) / det
        l2 = ((b[0] - a[0]) * (ys - a[1]) - (b[1] - a[1]) * (xs - a[0])) / det
        eps = 1e-6  # pixel centres on a shared edge belong to neither triangle
        inside = (l1 > eps) & (l2 > eps) & (1 - l1 - l2 > eps)
        iy = (ys[inside] - 0.5).astype(int)
        ix = (xs[inside] - 0.5).astype(int)
        cover[iy, ix] += 1
        label[iy, ix] = lab
    return cover, label


MESHES = {
    "cube1": lambda: cube(1.0),
    "cube3": lambda: cube(3.0),
    "cylinder": lambda: cylinder(),
}


@pytest.fixture
def cache(tmp_path) -> UVCache:
    return UVCache(tmp_path / "uv")


# -- unwrap ----------------------------------------------------------------------------------


@pytest.mark.parametrize("which", sorted(MESHES))
def test_unwrap_shapes_and_bounds(which, cache):
    mesh = MESHES[which]()
    a = unwrap(mesh, texels_per_metre=TPM, padding=2, cache=cache)
    assert a.st_indices.shape == mesh.face_vertex_indices.shape
    assert a.st_px.dtype == np.float32 and a.st_indices.dtype == np.int32
    assert np.all(a.st_px >= 0)
    assert np.all(a.st_px <= np.array([a.width, a.height]))
    assert a.chart_count >= 1 and 0 < a.utilisation <= 1
    assert a.texels_per_metre == TPM


def test_unwrap_keeps_corner_order_cube(cache):
    # every cube face is planar, so its chart is an isometry scaled by the density:
    # each UV edge is TPM times the 3D edge it stands for (corners matched one to one)
    mesh = cube(1.0)
    a = unwrap(mesh, texels_per_metre=TPM, padding=2, cache=cache)
    p3 = mesh.points[mesh.triangles]
    p2 = a.st_px.astype(np.float64)[a.st_indices.reshape(-1, 3)]
    for i, j in ((0, 1), (1, 2), (2, 0)):
        assert_allclose(
            np.linalg.norm(p2[:, j] - p2[:, i], axis=1),
            TPM * np.linalg.norm(p3[:, j] - p3[:, i], axis=1),
            rtol=0.02,
        )
    # 6 square faces: 6 charts unless xatlas merges coplanar-free neighbours (it must not)
    assert a.chart_count == 6


@pytest.mark.parametrize("which", sorted(MESHES))
def test_uv_triangles_keep_orientation_and_area(which, cache):
    mesh = MESHES[which]()
    a = unwrap(mesh, texels_per_metre=TPM, padding=2, cache=cache)
    area3 = face_normals(mesh.points, mesh.triangles)[1]
    area2 = uv_areas(a.st_px, a.st_indices)
    # no chart is mirrored: every UV triangle winds counter-clockwise like its face does
    # seen from outside (a mirrored chart flips tangent-space normal maps)
    assert np.all(area2[np.abs(area2) > 1e-9] > 0)
    assert_allclose(np.abs(area2).sum(), TPM**2 * area3.sum(), rtol=0.1)


def test_unwrap_tolerates_zero_area_triangles(cache):
    # a sliver (three collinear points along a cube edge) keeps its place in the face order
    c = cube(1.0)
    pts = np.vstack([c.points, [[0.5, 0.0, 0.0]]])
    idx = np.concatenate([c.face_vertex_indices, [0, 8, 4]])
    mesh = Mesh(pts, np.full(13, 3), idx)
    a = unwrap(mesh, texels_per_metre=TPM, cache=cache)
    assert a.st_indices.shape == (39,)
    area2 = uv_areas(a.st_px, a.st_indices)
    assert abs(area2[12]) < 1e-6
    assert_allclose(area2[:12].sum(), 6 * TPM**2, rtol=0.05)


def test_unwrap_rejects_polygons_and_bad_options(cache):
    quad = Mesh(np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float), [4], [0, 1, 2, 3])
    with pytest.raises(GeometryError, match="triangle"):
        unwrap(quad, texels_per_metre=TPM, cache=cache)
    with pytest.raises(GeometryError, match="no faces"):
        unwrap(Mesh(np.zeros((0, 3)), [], []), texels_per_metre=TPM, cache=cache)
    for kw in (
        {"texels_per_metre": 0.0},
        {"texels_per_metre": float("nan")},
        {"padding": -1},
        {"padding": 1.5},
        {"resolution_cap": 4},
    ):
        opts = {"texels_per_metre": TPM, **kw}
        with pytest.raises(ParameterError):
            unwrap(cube(1.0), cache=cache, **opts)
    with pytest.raises(ParameterError):
        unwrap(cube(1.0), texels_per_metre=TPM, cache="nope")
    assert cache.misses == 0  # options are checked before any look-up


# -- overlap ---------------------------------------------------------------------------------


@pytest.mark.parametrize("which,padding", [("cube3", 2), ("cylinder", 4), ("shaft", 4)])
def test_charts_do_not_overlap_and_keep_padding(which, padding, cache):
    if which == "shaft":
        from ionic_usd.column.shaft import ShaftParams, build_shaft

        mesh = build_shaft(ShaftParams(flute_slices=2))
        tpm = 48.0
    else:
        mesh, tpm = MESHES[which](), 64.0
    a = unwrap(mesh, texels_per_metre=tpm, padding=padding, cache=cache)
    charts = uv_charts(a.st_indices, len(a.st_px))
    cover, label = rasterise(a.st_px, a.st_indices, a.width, a.height, charts)
    assert cover.max() == 1, "a pixel centre lies inside two UV triangles"
    # the rasterised area matches the UV area: nothing folded over or lost
    assert_allclose((cover > 0).sum(), np.abs(uv_areas(a.st_px, a.st_indices)).sum(), rtol=0.1)
    # no pixel of another chart within `padding` texels (Chebyshev) of any chart pixel
    size = 2 * padding + 1
    hi = ndimage.maximum_filter(label, size=size, mode="constant", cval=-1)
    empty = int(label.max()) + 1
    lo = ndimage.minimum_filter(
        np.where(label < 0, empty, label), size=size, mode="constant", cval=empty
    )
    covered = label >= 0
    assert np.all(hi[covered] == label[covered]) and np.all(lo[covered] == label[covered])
    assert len(np.unique(charts)) == a.chart_count
    area2 = uv_areas(a.st_px, a.st_indices)
    assert np.all(area2[np.abs(area2) > 1e-9] > 0)  # no mirrored chart


def test_rasteriser_sees_overlaps_but_not_shared_edges():
    # the checker above must be able to fail: two copies of a triangle overlap, a square
    # split along its diagonal does not
    sq = np.array([[1, 1], [9, 1], [9, 9], [1, 9]], np.float32)
    cover, _ = rasterise(sq, np.array([0, 1, 2, 0, 2, 3]), 10, 10, np.array([0, 0]))
    # 8×8 pixel centres inside the square, minus the 8 centres on the diagonal edge
    assert cover.max() == 1 and (cover > 0).sum() == 64 - 8
    cover, _ = rasterise(sq, np.array([0, 1, 2, 0, 1, 2]), 10, 10, np.array([0, 1]))
    assert cover.max() == 2


# -- apply_uvs and texel density -------------------------------------------------------------


def test_apply_uvs_consistent_texel_density(cache):
    parts = {"small": cube(1.0, "small"), "big": cube(3.0, "big"), "cyl": cylinder()}
    out = apply_uvs(parts, texels_per_metre=TPM, padding=4, cache=cache)
    assert list(out) == list(parts)
    atlases = unwrap_parts(parts, texels_per_metre=TPM, padding=4, cache=cache)
    s = common_atlas_size(atlases.values())
    assert s & (s - 1) == 0 and s >= max(a.size for a in atlases.values()) > s // 2
    density = {}
    for k, m in out.items():
        assert m.st.values.min() >= 0 and m.st.values.max() <= 1
        surface = face_normals(m.points, m.triangles)[1].sum()
        density[k] = np.abs(uv_areas(m.st.values, m.st.indices)).sum() / surface
    # the same fraction of an S×S texture per square metre on every part, namely (TPM / S)²
    for k in density:
        assert_allclose(density[k], (TPM / s) ** 2, rtol=0.15, err_msg=k)
    assert max(density.values()) / min(density.values()) < 1.15


def test_apply_uvs_keeps_geometry(cache):
    mesh = smooth_normals(cylinder(segments=24))
    before = (
        mesh.points.copy(),
        mesh.face_vertex_counts.copy(),
        mesh.face_vertex_indices.copy(),
        mesh.normals.values.copy(),
    )
    out = apply_uvs({"c": mesh}, texels_per_metre=TPM, cache=cache)["c"]
    assert_array_equal(out.points, before[0])
    assert_array_equal(out.face_vertex_counts, before[1])
    assert_array_equal(out.face_vertex_indices, before[2])
    assert_array_equal(out.normals.values, before[3])
    assert out.normals.by_point == mesh.normals.by_point
    assert len(boundary_edges(out)) == 0  # still watertight
    assert out.st.dim == 2 and out.st.indices.shape == out.face_vertex_indices.shape
    assert mesh.st is None  # the input is not modified


def test_explicit_atlas_size_scales_uvs(cache):
    parts = {"a": cube(1.0)}
    base = apply_uvs(parts, texels_per_metre=TPM, cache=cache)["a"]
    s = common_atlas_size(unwrap_parts(parts, texels_per_metre=TPM, cache=cache).values())
    double = apply_uvs(parts, texels_per_metre=TPM, cache=cache, atlas_size=2 * s)["a"]
    assert_allclose(double.st.values, base.st.values / 2, rtol=1e-6)
    assert_array_equal(double.st.indices, base.st.indices)
    atlas = unwrap(cube(1.0), texels_per_metre=TPM, cache=cache)
    with pytest.raises(ParameterError, match="atlas_size"):
        apply_uvs(parts, texels_per_metre=TPM, cache=cache, atlas_size=atlas.size - 1)


def test_variant_alternatives_share_scale(cache):
    # two alternative bases for one LOD: one S for both keeps their texel density equal
    alts = {"narrow": cylinder(0.4, 0.5), "wide": cylinder(1.2, 0.5)}
    s = common_atlas_size(unwrap_parts(alts, texels_per_metre=TPM, cache=cache).values())
    narrow = apply_uvs({"b": alts["narrow"]}, texels_per_metre=TPM, cache=cache, atlas_size=s)
    wide = apply_uvs({"b": alts["wide"]}, texels_per_metre=TPM, cache=cache, atlas_size=s)
    d = [
        np.abs(uv_areas(m["b"].st.values, m["b"].st.indices)).sum()
        / face_normals(m["b"].points, m["b"].triangles)[1].sum()
        for m in (narrow, wide)
    ]
    assert_allclose(d[0], d[1], rtol=0.15)


def test_resolution_cap_lowers_density_for_all_parts(cache):
    parts = {"small": cube(1.0), "big": cube(10.0)}
    cap = 256
    atlases = unwrap_parts(parts, texels_per_metre=64.0, resolution_cap=cap, cache=cache)
    big = atlases["big"]
    assert big.size <= cap and big.texels_per_metre < 64.0
    assert atlases["small"].texels_per_metre == big.texels_per_metre
    out = apply_uvs(parts, texels_per_metre=64.0, resolution_cap=cap, cache=cache)
    d = {
        k: np.abs(uv_areas(m.st.values, m.st.indices)).sum()
        / face_normals(m.points, m.triangles)[1].sum()
        for k, m in out.items()
    }
    assert_allclose(d["small"], d["big"], rtol=0.15)


def test_attach_uvs_checks_corner_count(cache):
    a = unwrap(cube(1.0), texels_per_metre=TPM, cache=cache)
    with pytest.raises(GeometryError, match="corners"):
        attach_uvs(cylinder(), a)


def test_uvatlas_validates():
    with pytest.raises(GeometryError):
        UVAtlas(np.zeros((3, 2)), np.array([0, 1, 5]), 8, 8, 1, 0.5, 1.0)
    with pytest.raises(GeometryError):
        UVAtlas(np.array([[0, 0], [9, 0], [0, 1]]), np.array([0, 1, 2]), 8, 8, 1, 0.5, 1.0)
    with pytest.raises(ParameterError):
        UVAtlas(np.zeros((3, 2)), np.array([0, 1, 2]), 0, 8, 1, 0.5, 1.0)
    a = UVAtlas(np.array([[0, 0], [6, 0], [0, 5]]), np.array([0, 1, 2]), 6, 5, 1, 0.5, 1.0)
    assert_allclose(a.st(), [[0, 0], [6 / 8, 0], [0, 5 / 8]])  # 6 rounds up to 8
    with pytest.raises(ParameterError):
        a.st(4)


# -- cache ------------------------------------------------------------------------------------


def test_cache_hit_and_persistence(tmp_path):
    folder = tmp_path / "uv"
    c = UVCache(folder)
    mesh = cylinder()
    first = unwrap(mesh, texels_per_metre=TPM, cache=c)
    assert (c.hits, c.misses) == (0, 1)
    second = unwrap(mesh, texels_per_metre=TPM, cache=c)
    assert (c.hits, c.misses) == (1, 1)
    assert second is first  # served from memory
    files = list(folder.iterdir())
    assert [f.suffix for f in files] == [".npz"]  # no temporary file left behind
    fresh = UVCache(folder)
    third = unwrap(mesh, texels_per_metre=TPM, cache=fresh)
    assert (fresh.hits, fresh.disk_hits, fresh.misses) == (1, 1, 0)
    assert_array_equal(third.st_px, first.st_px)
    assert_array_equal(third.st_indices, first.st_indices)
    assert (third.width, third.height, third.chart_count) == (
        first.width,
        first.height,
        first.chart_count,
    )
    # a rebuild of several parts does no unwrapping at all
    parts = {"a": cube(1.0), "b": mesh}
    apply_uvs(parts, texels_per_metre=TPM, cache=fresh)
    misses = fresh.misses
    apply_uvs(parts, texels_per_metre=TPM, cache=UVCache(folder))
    assert misses == 1  # only the cube was new
    rebuilt = UVCache(folder)
    apply_uvs(parts, texels_per_metre=TPM, cache=rebuilt)
    assert rebuilt.misses == 0 and rebuilt.hits == 2


def test_cache_key_depends_on_inputs():
    m = cube(1.0)
    k = uv_cache_key(m, texels_per_metre=TPM, padding=4)
    assert k == uv_cache_key(cube(1.0), texels_per_metre=TPM, padding=4)
    moved = m.with_(points=m.points + [0.0, 1e-9, 0.0])
    others = {
        uv_cache_key(m, texels_per_metre=TPM * 2, padding=4),
        uv_cache_key(m, texels_per_metre=TPM, padding=2),
        uv_cache_key(m, texels_per_metre=TPM, padding=4, resolution_cap=1024),
        uv_cache_key(moved, texels_per_metre=TPM, padding=4),
        uv_cache_key(
            m.with_(face_vertex_indices=m.face_vertex_indices[::-1]),
            texels_per_metre=TPM,
            padding=4,
        ),
    }
    assert len(others) == 5 and k not in others


@pytest.mark.parametrize("damage", ["garbage", "truncated", "empty", "foreign"])
def test_corrupt_cache_file_is_rewritten(tmp_path, damage):
    folder = tmp_path / "uv"
    mesh = cube(1.0)
    good = unwrap(mesh, texels_per_metre=TPM, cache=UVCache(folder))
    key = uv_cache_key(mesh, texels_per_metre=TPM, padding=4)
    path = UVCache(folder).path_for(key)
    data = path.read_bytes()
    if damage == "garbage":
        path.write_bytes(b"not a zip file at all" * 10)
    elif damage == "truncated":
        path.write_bytes(data[: len(data) // 2])
    elif damage == "empty":
        path.write_bytes(b"")
    else:  # a valid file stored under another key
        unwrap(cube(2.0), texels_per_metre=TPM, cache=UVCache(folder))
        other = uv_cache_key(cube(2.0), texels_per_metre=TPM, padding=4)
        path.write_bytes(UVCache(folder).path_for(other).read_bytes())
    c = UVCache(folder)
    again = unwrap(mesh, texels_per_metre=TPM, cache=c)
    assert (c.corrupt, c.misses, c.hits) == (1, 1, 0)
    assert_array_equal(again.st_px, good.st_px)
    check = UVCache(folder)  # the file was rewritten and now reads back
    unwrap(mesh, texels_per_metre=TPM, cache=check)
    assert (check.corrupt, check.disk_hits, check.misses) == (0, 1, 0)


def test_unwritable_cache_folder_only_disables_files(tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("x")
    c = UVCache(blocker / "uv")  # a folder below a regular file cannot be created
    unwrap(cube(1.0), texels_per_metre=TPM, cache=c)
    unwrap(cube(1.0), texels_per_metre=TPM, cache=c)
    assert (c.hits, c.misses) == (1, 1)


def test_memory_only_and_disabled_cache(tmp_path):
    c = UVCache(tmp_path / "uv", persist=False)
    unwrap(cube(1.0), texels_per_metre=TPM, cache=c)
    unwrap(cube(1.0), texels_per_metre=TPM, cache=c)
    assert (c.hits, c.misses) == (1, 1) and not (tmp_path / "uv").exists()
    a = unwrap(cube(1.0), texels_per_metre=TPM, cache=False)
    assert a.st_indices.size == 36


def test_default_cache_folder(monkeypatch, tmp_path):
    monkeypatch.setenv("IONIC_USD_CACHE", str(tmp_path / "c"))
    assert default_cache_folder() == tmp_path / "c" / "uv"
    monkeypatch.delenv("IONIC_USD_CACHE")
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "x"))
    assert default_cache_folder() == tmp_path / "x" / "ionic_usd" / "uv"
    monkeypatch.delenv("XDG_CACHE_HOME")
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    assert default_cache_folder() == tmp_path / "home" / ".cache" / "ionic_usd" / "uv"


# -- analytic charts ---------------------------------------------------------------------------


def test_analytic_charts_are_packed_without_xatlas_at_the_density(cache):
    from ionic_usd.column.base import build_base, load_base_preset
    from ionic_usd.column.shaft import ShaftParams, build_shaft

    parts = {
        "shaft": build_shaft(ShaftParams(flute_slices=3)),
        "base": build_base(load_base_preset("G2", segments=48)),
    }
    atlases = unwrap_parts(parts, texels_per_metre=TPM, cache=cache)
    assert cache.misses == 0 and cache.hits == 0  # no xatlas run, no cache entry
    for name, a in atlases.items():
        m = parts[name]
        assert a.texels_per_metre == TPM
        _, area3 = face_normals(m.points, m.triangles)
        # charts are only translated: pixel area = metric st area × density²
        assert_allclose(
            uv_areas(a.st_px, a.st_indices).sum(),
            uv_areas(m.st.values, m.st.indices).sum() * TPM**2,
            rtol=1e-4,
        )
        assert 0.2 < a.utilisation <= 1.0
    out = apply_uvs(parts, texels_per_metre=TPM, cache=cache)
    for m in out.values():
        v = m.st.values
        assert np.all(np.isfinite(v)) and v.min() >= 0.0 and v.max() <= 1.0


def test_an_analytic_atlas_is_kept_with_its_mesh_and_travels_with_it():
    """The packing is derived data of the mesh: made once per (density, padding, cap), carried
    through pickling (a pool worker packs, the parent reuses), never carried to a new mesh."""
    import pickle

    from ionic_usd.column.shaft import ShaftParams, build_shaft
    from ionic_usd.texture.atlas import analytic_atlas

    mesh = build_shaft(ShaftParams(flute_slices=3))
    a = analytic_atlas(mesh, texels_per_metre=64)
    assert analytic_atlas(mesh, texels_per_metre=64) is a
    b = analytic_atlas(mesh, texels_per_metre=32)
    assert b is not a and b.texels_per_metre == 32 and b.width < a.width
    assert analytic_atlas(mesh, texels_per_metre=64, padding=0) is not a
    travelled = pickle.loads(pickle.dumps(mesh))
    fresh = mesh.with_(name=mesh.name)  # a new value: no derived data
    for other in (
        analytic_atlas(travelled, texels_per_metre=64),
        analytic_atlas(fresh, texels_per_metre=64),
    ):
        assert other is not a
        assert_array_equal(other.st_px, a.st_px)
        assert_array_equal(other.st_indices, a.st_indices)
        assert (other.width, other.height, other.chart_count) == (a.width, a.height, a.chart_count)
    # a mesh edited after packing is a new value and is packed again
    moved = mesh.with_(st=mesh.st.with_values(mesh.st.values * 2))
    assert analytic_atlas(moved, texels_per_metre=64).width > a.width


def test_metric_charts_let_cuts_reuse_one_unwrap(cache):
    from ionic_usd.geometry.clip import clip_mesh
    from ionic_usd.texture.uv import metric_charts

    (charted,) = metric_charts([cylinder()], TPM, cache=cache)
    assert cache.misses == 1 and charted.st is not None
    half = clip_mesh(charted, (0.0, 0.0, 0.0), (0.0, 0.0, 1.0))
    assert half.st is not None
    a = unwrap(half, texels_per_metre=TPM, cache=cache)
    assert cache.misses == 1  # the cut's charts are packed, not unwrapped again
    areas = uv_areas(a.st_px, a.st_indices)
    assert np.all(areas[np.abs(areas) > 1e-9] > 0)


# -- charts that overlap themselves ----------------------------------------------------------


def overlap_texels(st_px: np.ndarray, st_indices: np.ndarray, scale: int = 4) -> int:
    """Sub-texels (a ``scale``× finer raster of the atlas) covered by two triangles."""
    st_px = np.asarray(st_px, dtype=np.float64) * scale
    w, h = (int(np.ceil(v)) + 1 for v in st_px.max(axis=0))
    charts = uv_charts(st_indices, len(st_px))
    cover, _ = rasterise(st_px, st_indices, w, h, charts)
    return int((cover > 1).sum())


def test_split_overlapping_charts_separates_a_fold():
    from ionic_usd.texture.charts import overlapping_triangles, split_overlapping_charts

    # chart 0: a square (triangles 0, 1) and triangle 2 folded back over it across edge DC,
    # every triangle counter-clockwise; chart 1 elsewhere touches nothing
    st = np.array(
        [[0, 0], [1, 0], [0, 1], [1, 1], [0.2, 0.2], [3, 0], [4, 0], [3, 1]], dtype=np.float64
    )
    sti = np.array([0, 1, 2, 1, 3, 2, 3, 2, 4, 5, 6, 7])
    assert np.all(uv_areas(st, sti) > 0)
    assert {tuple(p) for p in overlapping_triangles(st, sti, 1e-9).tolist()} == {(0, 2), (1, 2)}
    st2, sti2, n = split_overlapping_charts(st, sti, 1e-9)
    assert n == 1
    assert len(overlapping_triangles(st2, sti2, 1e-9)) == 0
    labels = uv_charts(sti2, len(st2))
    assert labels[0] == labels[1] != labels[2] and len(set(labels.tolist())) == 3
    assert_array_equal(st2[sti2], st[sti])  # every corner keeps its value
    # touching neighbours (shared edges and vertices) are not overlaps
    ok = np.array([0, 1, 2, 1, 3, 2, 5, 6, 7])
    assert len(overlapping_triangles(st, ok, 1e-9)) == 0
    assert split_overlapping_charts(st, ok, 1e-9)[2] == 0


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_overlapping_triangles_match_geos_on_every_pair(seed):
    # a soup of random triangles, some snapped to a coarse grid so that many touch exactly
    # along edges and at vertices: the broad phase (R-tree) and the separating-axis test
    # together must report exactly the pairs GEOS's intersection gives an area, checked pair
    # by pair over all n (n - 1) / 2 pairs
    import shapely

    from ionic_usd.texture.charts import overlapping_triangles

    rng = np.random.default_rng(seed)
    n = 120
    st = rng.random((3 * n, 2)) * 4.0
    st[: 3 * n // 2] = np.round(st[: 3 * n // 2] * 2) / 2
    tri = st.reshape(-1, 3, 2)
    cross = (tri[:, 1, 0] - tri[:, 0, 0]) * (tri[:, 2, 1] - tri[:, 0, 1]) - (
        tri[:, 1, 1] - tri[:, 0, 1]
    ) * (tri[:, 2, 0] - tri[:, 0, 0])
    tri = tri[np.abs(cross) > 1e-3]  # no degenerate triangles (GEOS and SAT disagree on those)
    st = tri.reshape(-1, 2)
    sti = np.arange(len(st))
    polys = shapely.polygons(np.concatenate([tri, tri[:, :1]], axis=1))
    want = {
        (i, j)
        for i in range(len(tri))
        for j in range(i + 1, len(tri))
        if shapely.intersection(polys[i], polys[j]).area > 1e-9
    }
    got = {tuple(p) for p in overlapping_triangles(st, sti, 1e-9, same_chart=False).tolist()}
    assert len(want) > 20
    assert got == want


def test_metric_charts_of_a_low_capital_do_not_overlap(cache):
    # xatlas folds one chart of this capital onto itself (3 triangle pairs); repacked, the
    # fold covered 26 sub-texels of a 4x raster twice before its charts were split
    from ionic_usd.blueprint.column_asset import ColumnAssetOptions
    from ionic_usd.column.column import build_capital_part
    from ionic_usd.lod import level
    from ionic_usd.texture.uv import metric_charts

    p = ColumnAssetOptions().params.with_lod("low")
    body = build_capital_part(p, 0.0, scroll="S1")
    tpm = level("low").asset_texels_per_metre
    (charted,) = metric_charts([body], tpm, cache=cache)
    a = unwrap(charted, texels_per_metre=tpm, cache=cache)
    assert overlap_texels(a.st_px, a.st_indices) == 0
