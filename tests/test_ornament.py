"""Ornament prototypes (closed, tiny) and their placement rules (Vitruvius where he gives one)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from numpy.testing import assert_allclose

from ionic_usd.column.column import portunus_column_params
from ionic_usd.column.ornament import (
    capital_ornament,
    frames_to_quaternions,
    quaternion_matrices,
)
from ionic_usd.errors import ParameterError
from ionic_usd.temple.layout import portunus_layout
from ionic_usd.temple.mouldings import cornice_levels
from ionic_usd.temple.ornament import (
    TileParams,
    dentil_spacing,
    dentils,
    frieze_garlands,
    roof_tiles,
)


@pytest.fixture(scope="module")
def layout():
    return portunus_layout()


@pytest.fixture(scope="module")
def capital():
    p = portunus_column_params()
    return capital_ornament(
        y_capital=7.0,
        top_radius=p.shaft.top_radius,
        echinus_height=p.capital.echinus_height,
        echinus_projection=p.capital.echinus_projection,
        ring_top=p.shaft.ring_top,
    )


def _closed(m) -> bool:
    import manifold3d as m3

    man = m3.Manifold(
        m3.Mesh(
            vert_properties=m.points.astype(np.float32), tri_verts=m.triangles.astype(np.uint32)
        )
    )
    return str(man.status()) == "Error.NoError" and man.volume() > 0


def test_every_prototype_is_a_small_closed_solid(layout, capital):
    sets = [dentils(layout), roof_tiles(layout), frieze_garlands(layout), *capital]
    protos = [p for s in sets for p in s.prototypes]
    assert {p.name for p in protos} == {
        "Dentil",
        "Tegula",
        "Imbrex",
        "Antefix",
        "Candelabrum",
        "Garland",
        "Egg",
        "Dart",
        "Bead",
        "Reel",
    }
    for p in protos:
        assert _closed(p), p.name
        assert p.n_triangles <= 300, p.name


def test_quaternions_match_the_frames(rng):
    x = rng.normal(size=(200, 3))
    y = np.cross(x, rng.normal(size=(200, 3)))
    q = frames_to_quaternions(x, y)
    assert_allclose(np.linalg.norm(q, axis=1), 1.0)
    r = quaternion_matrices(q)
    assert_allclose(r[:, :, 0], x / np.linalg.norm(x, axis=1, keepdims=True), atol=1e-12)
    assert_allclose(r[:, :, 1], y / np.linalg.norm(y, axis=1, keepdims=True), atol=1e-12)
    assert_allclose(np.linalg.det(r), 1.0)


def test_dentils_follow_vitruvius(layout):
    lv = cornice_levels(layout)
    h = lv["dentil_top"] - lv["dentil_bottom"]
    w, s = dentil_spacing(h)
    assert w == pytest.approx(h / 2) and s - w == pytest.approx(2 * w / 3)  # III.5.11
    d = dentils(layout)
    # per side: as many as fit on the band face, centred, one every 5/6 of the height
    fx, fz = lv["xe"] + lv["dentil_face"], lv["ze"] + lv["dentil_face"]
    per_side = [math.floor((2 * fx - w) / s) + 1, math.floor((2 * fz - w) / s) + 1]
    assert len(d) == 2 * sum(per_side)
    front = d.positions[np.isclose(d.positions[:, 2], fz)]
    assert len(front) == per_side[0]
    assert_allclose(np.diff(np.sort(front[:, 0])), s)
    assert_allclose(front[:, 0].mean(), 0.0, atol=1e-12)
    # density: dentils per metre of cornice band = 1/s (6/(5h))
    assert len(front) / (2 * fx) == pytest.approx(1 / s, rel=0.05)
    # the dentil projects its own height out of the band, within the corona's soffit
    proto = d.prototypes[0]
    assert_allclose(proto.extent[1, 2], lv["dentil_front"] - lv["dentil_face"])
    assert_allclose(proto.extent[1, 1] - proto.extent[0, 1], h)


@pytest.mark.parametrize(
    "kw, name",
    [
        ({"thickness": 0.0}, "thickness"),
        ({"flange": float("nan")}, "flange"),
        ({"antefix_height": True}, "antefix_height"),
        ({"overlap": 0.62}, "overlap"),
    ],
)
def test_tile_parameters_are_checked(kw, name):
    with pytest.raises(ParameterError) as info:
        TileParams(**kw)
    assert info.value.name == name and str(info.value).startswith("tiles: ")


def test_roof_tiles_cover_both_slabs(layout):
    tp = TileParams()
    t = roof_tiles(layout, tp)
    lv = cornice_levels(layout)
    p = layout.params
    xc, zc = lv["xe"] + lv["projection"], lv["ze"] + lv["projection"]
    phi = math.atan(2 / p.roof_tympanum_ratio)
    rows = math.ceil((xc / math.cos(phi) - tp.tegula_length) / (tp.tegula_length - tp.overlap)) + 1
    cols = round(2 * zc / tp.tegula_width)
    c = t.counts()
    assert c == {
        "Tegula": 2 * rows * cols,
        "Imbrex": 2 * rows * (cols - 1),
        "Antefix": 2 * (cols - 1),
    }
    # its local +Y is the slab's normal (tilted by the pitch)
    r = quaternion_matrices(t.orientations[t.proto_indices == 0])
    assert_allclose(np.degrees(np.arccos(r[:, 1, 1])), math.degrees(phi), atol=1e-9)


def _placed(t, kind: int) -> list[np.ndarray]:
    """World points of every copy of prototype ``kind`` (scale, rotate, move)."""
    m = t.prototypes[kind]
    sel = np.flatnonzero(t.proto_indices == kind)
    r = quaternion_matrices(t.orientations[sel])
    return [(m.points * t.scales[i]) @ r[j].T + t.positions[i] for j, i in enumerate(sel)]


@pytest.mark.parametrize("apply", [(), ("roof-pitch-15",)])
def test_roof_tiles_lie_on_the_slab_and_leave_no_gap(apply):
    """The tiles rest on the slab mesh itself (none sinks into it, so the slab cannot show
    through a pan), and the tegulae close each slab: side by side across (no slot between
    neighbours), overlapping up the slope, from the eaves to the ridge."""
    from ionic_usd.temple import cuboid_mesh
    from ionic_usd.temple.layout import Layer

    layout = portunus_layout(apply=apply)
    t = roof_tiles(layout)
    for name, sgn in (("roof_left", -1.0), ("roof_right", 1.0)):
        slab = next(c for c in layout.cuboids[Layer.ROOF] if c.name == name)
        sm = cuboid_mesh(slab)
        # the slab's top: its face whose normal points most upward, from the mesh itself
        faces = np.split(sm.face_vertex_indices, np.cumsum(sm.face_vertex_counts)[:-1])
        normals = [np.cross(*(sm.points[f[1:3]] - sm.points[f[0]])) for f in faces]
        k = int(np.argmax([nn[1] / np.linalg.norm(nn) for nn in normals]))
        top, n = sm.points[faces[k]], normals[k] / np.linalg.norm(normals[k])
        up = -sgn * np.array([n[1], -n[0], 0.0])  # up the slope
        eave = top[np.argmin(top[:, 1])]
        slope = float(np.max((top - eave) @ up))
        half = float(np.max(np.abs(top[:, 2])))
        tiles = [w for k in (0, 1) for w in _placed(t, k) if np.sign(w[:, 0].mean()) == sgn]
        heights = np.concatenate([(w - eave) @ n for w in tiles])
        assert heights.min() > -1e-9, f"{name}: a tile sinks {-heights.min():.3f} m into it"
        # tegula footprints on the slab: (along the slope, across) intervals
        teg = [w for w in _placed(t, 0) if np.sign(w[:, 0].mean()) == sgn]
        a = np.array([[((w - eave) @ up).min(), ((w - eave) @ up).max()] for w in teg])
        z = np.array([[w[:, 2].min(), w[:, 2].max()] for w in teg])
        rows = np.unique(np.round(a[:, 0], 6))
        for lo in rows:
            zr = z[np.abs(a[:, 0] - lo) < 1e-6]
            zr = zr[np.argsort(zr[:, 0])]
            assert zr[0, 0] <= -half + 1e-6 and zr[-1, 1] >= half - 1e-6
            assert np.all(zr[1:, 0] <= zr[:-1, 1] + 1e-6), f"{name}: a slot between tegulae"
        ar = np.unique(np.round(a, 6), axis=0)
        assert ar[0, 0] <= 1e-6 and ar[-1, 1] >= slope - 1e-6
        assert np.all(ar[1:, 0] < ar[:-1, 1]), f"{name}: a course does not reach the next"


def test_capital_ornament_rings(capital):
    egg, bead = capital
    assert egg.counts() == {"Egg": 24, "Dart": 24}
    p = portunus_column_params()
    c = p.shaft.top_radius
    n = bead.counts()["Bead"]
    assert bead.counts()["Reel"] == n
    # beads ring the astragal at the shaft's top radius, inside the top ring's height
    r = np.hypot(bead.positions[:, 0], bead.positions[:, 2])
    assert_allclose(r, c)
    assert np.all((bead.positions[:, 1] < 7.0) & (bead.positions[:, 1] > 7.0 - p.shaft.ring_top))
    # eggs face outwards and down the ovolo: local +Z has a positive radial component
    z = quaternion_matrices(egg.orientations)[:, :, 2]
    radial = egg.positions * [1, 0, 1] / np.hypot(egg.positions[:, 0], egg.positions[:, 2])[:, None]
    assert np.all(np.einsum("ij,ij->i", z, radial) > 0.5) and np.all(z[:, 1] < 0)


def test_frieze_garlands_alternate_on_the_frieze(layout):
    f = frieze_garlands(layout)
    lv = cornice_levels(layout)
    c = f.counts()
    assert c["Garland"] == c["Candelabrum"] - 4  # one fewer per side
    assert np.all((f.positions[:, 1] > lv["y_frieze"]) & (f.positions[:, 1] < lv["y_cornice"]))


def test_every_prototype_has_outward_normals(layout, capital):
    """Renderers and NVIDIA's NormalsExistChecker want normals on every prototype; the tiles'
    are carried through their shear (inverse transpose), so each corner's normal still leans
    outward from its face (within the sweep's smoothing of gentle section corners)."""
    sets = [dentils(layout), roof_tiles(layout), frieze_garlands(layout), *capital]
    for p in (p for s in sets for p in s.prototypes):
        assert p.normals is not None, p.name
        n = np.asarray(p.normals.values, dtype=np.float64)
        assert_allclose(np.linalg.norm(n, axis=1), 1.0, atol=1e-3, err_msg=p.name)
        tri = p.triangles
        a, b, c = (p.points[tri[:, k]] for k in range(3))
        face = np.cross(b - a, c - a)
        face /= np.linalg.norm(face, axis=1, keepdims=True)
        if not p.normals.by_point:
            n = np.asarray(p.corner_normals(), dtype=np.float64)
            # fan triangulation: triangle t of face f uses corners 0, k, k+1 of that face
            counts = p.face_vertex_counts
            starts = np.concatenate([[0], np.cumsum(counts)[:-1]])
            corner = np.concatenate(
                [
                    starts[f] + np.array([0, k, k + 1])
                    for f, cnt in enumerate(counts)
                    for k in range(1, cnt - 1)
                ]
            )
            per = n[corner].reshape(-1, 3, 3)
        else:
            per = n[tri]
        cos = np.einsum("tj,tkj->tk", face, per)
        assert cos.min() > 0.0, p.name
