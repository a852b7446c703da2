"""Mouldings swept along the temple: closed, sized by the layout, data in the TOML."""

from __future__ import annotations

import numpy as np
import pytest
from numpy.testing import assert_allclose

from ionic_usd.errors import GrammarError, ParameterError
from ionic_usd.geometry.sweep import polygon_area
from ionic_usd.temple.layout import portunus_layout
from ionic_usd.temple.mouldings import (
    MouldingParams,
    _close,
    cornice_levels,
    moulding_meshes,
    moulding_section,
    mouldings_from_tables,
    portunus_mouldings,
)


@pytest.fixture(scope="module")
def members():
    return {m.name: m for m in moulding_meshes(portunus_layout())}


def test_every_member_is_a_closed_outward_solid(members):
    import manifold3d as m3

    assert set(members) == {
        "architrave",
        "cornice",
        "sima_left",
        "sima_right",
        "podium_base",
        "podium_crown",
        "raking_cornice_front",
        "raking_cornice_rear",
    }
    for m in members.values():
        man = m3.Manifold(
            m3.Mesh(
                vert_properties=m.mesh.points.astype(np.float32),
                tri_verts=m.mesh.triangles.astype(np.uint32),
            )
        )
        assert str(man.status()) == "Error.NoError", m.name
        assert man.volume() > 0, m.name
        assert np.all(np.isfinite(m.mesh.st.values)) and m.mesh.normals is not None


def _centroid_u(sec: np.ndarray) -> tuple[float, float]:
    p, q = sec, np.roll(sec, -1, axis=0)
    cr = p[:, 0] * q[:, 1] - q[:, 0] * p[:, 1]
    a = cr.sum() / 2
    return abs(a), float(((p[:, 0] + q[:, 0]) * cr).sum() / (6 * a))


def test_architrave_volume_by_pappus_for_a_mitred_rectangle(members):
    # a section of area A and centroid offset ū swept round a W × L rectangle with mitres:
    # V = A · (2W + 2L + 8ū)  (the perimeter at offset u is 2W + 2L + 8u)
    lay = portunus_layout()
    lv = cornice_levels(lay)
    a = lay.params.entablature_heights[0]
    sec = _close(
        moulding_section(MouldingParams().architrave, a), 2 * lv["half_top"], chamfer=False
    )
    area, ubar = _centroid_u(sec)
    want = area * (4 * lv["xe"] + 4 * lv["ze"] + 8 * ubar)
    m = members["architrave"].mesh
    from ionic_usd.geometry.analysis import signed_volume

    assert_allclose(signed_volume(m), want, rtol=1e-9)


def test_sections_follow_vitruvius(members):
    lay = portunus_layout()
    a, f, c = lay.params.entablature_heights
    arch = moulding_section(MouldingParams().architrave, a)
    assert_allclose(arch[-1, 1], a)  # three fasciae + cymatium fill the architrave
    # cymatium 1/7 of the architrave, projecting its own height beyond the third fascia
    assert_allclose(arch[-1, 0] - 0.06 * a, a / 7, rtol=2e-3)
    cor = moulding_section(MouldingParams().cornice, c)
    sima = moulding_section(MouldingParams().sima, c)
    assert_allclose(cor[-1, 1] + sima[-1, 1], c)  # corona top + sima = the cornice height
    assert_allclose(sima[-1, 1] / (cor[-1, 1] - cor[-2, 1]), 9 / 8, rtol=2e-3)  # III.5.12
    assert_allclose(sima[:, 0].max(), c * lay.params.entablature_cornice_projection_ratio)
    # the members sit where the plain cuboids were: cornice from the frieze top to its top
    ext = members["cornice"].mesh.extent
    lv = cornice_levels(lay)
    assert_allclose([ext[0, 1], ext[1, 1]], [lv["y_cornice"], lv["y_top"]])
    # the sima crowns the flanks only, out to the cornice projection, ending at the corona's
    # front and rear faces
    for side, sgn in (("sima_left", -1), ("sima_right", 1)):
        e = members[side].mesh.extent
        assert_allclose(e[1 if sgn > 0 else 0, 0], sgn * (lv["xe"] + lv["projection"]))
        assert_allclose(
            [e[0, 2], e[1, 2]], [-lv["ze"] - lv["projection"], lv["ze"] + lv["projection"]]
        )
        assert_allclose(e[1, 1], lv["y_top"])
    # raking cornice: under the roof slab's soffit, projecting as far as the cornice
    rk = members["raking_cornice_front"].mesh.extent
    assert_allclose(rk[1, 2], lv["ze"] + lv["projection"])
    ridge = (lv["xe"] + lv["projection"]) * 2 / lay.params.roof_tympanum_ratio
    assert rk[1, 1] <= lv["y_top"] + ridge + 1e-9


def test_podium_mouldings_stop_at_the_stairs(members):
    lay = portunus_layout()
    p = lay.params
    w2, cw = p.stylobate_width / 2, p.podium_cheek_wall_width
    front = p.stylobate_length / 2 + p.stair_run
    for name in ("podium_base", "podium_crown"):
        pts = members[name].mesh.points
        at_front = pts[np.abs(pts[:, 2] - pts[:, 2].max()) < 1e-9]
        assert pts[:, 2].max() > front  # the cheek walls' fronts are moulded too
        # nothing crosses the stair opening between the cheek walls
        inside = (np.abs(pts[:, 0]) < w2 - cw - 1e-9) & (pts[:, 2] > p.stylobate_length / 2)
        assert not inside.any(), name
        assert len(at_front)


def test_toml_table_matches_defaults_and_is_validated():
    assert portunus_mouldings() == MouldingParams()
    with pytest.raises(ParameterError, match="mouldings.fascia"):
        mouldings_from_tables({"mouldings": {"fascia": "R0 H1"}})
    with pytest.raises(GrammarError) as info:
        mouldings_from_tables({"mouldings": {"cornice": "R0 H0 Rx H1"}})
    # relabelled twice (the moulding, then the table's context), caret still under the token
    assert info.value.grammar == "temple: mouldings.cornice (base v2)"
    assert (info.value.source, info.value.offset, info.value.module) == ("R0 H0 Rx H1", 7, 1)
    assert str(info.value).startswith("temple: mouldings.cornice (base v2) error in module 1")
    with pytest.raises(ParameterError, match="podium_back"):
        MouldingParams(podium_back=-1.0)


def test_close_keeps_faces_off_the_face_plane_with_chamfer():
    curve = np.array([[0.1, 0.0], [0.1, 0.5], [0.0, 1.0]])
    sec = _close(curve, 0.2, chamfer=True)
    on_plane = np.abs(sec[:, 0]) < 1e-12
    # only the bottom and top corner touch u = 0: no section edge lies in the face plane
    assert sorted(sec[on_plane, 1].tolist()) == [0.0, 1.0]
    assert polygon_area(sec) != 0
