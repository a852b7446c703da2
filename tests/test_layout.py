"""Temple layouts: the Portunus preset, column placements, roof pitch, TOML loading."""

from __future__ import annotations

import math
import subprocess
import sys
import tomllib
from importlib import resources

import numpy as np
import pytest
from numpy.testing import assert_allclose

from ionic_usd.errors import ParameterError
from ionic_usd.geometry import inspect_mesh
from ionic_usd.temple import (
    ColumnKind,
    ColumnPlacement,
    Cuboid,
    Incline,
    Layer,
    TempleParams,
    build_layout,
    colonnade_positions,
    cuboid_mesh,
    cuboid_points,
    cuboids_to_toml,
    layout_from_toml,
    load_cuboids_toml,
    portunus_layout,
)
from ionic_usd.temple.layout import ROOF_BED

W, L, H_COL, D = 10.50, 19.30, 8.22, 0.95  # the brief's figures, restated independently
PODIUM_H = 2.40


@pytest.fixture(scope="module")
def lay():
    return portunus_layout()


def _inside(c: Cuboid, pts: np.ndarray, tol: float = 1e-7) -> np.ndarray:
    """Vectorised strict point-in-solid test, written from the definition."""
    x, y, z = pts.T
    t = (x - c.min[0]) / (c.max[0] - c.min[0])
    top = c.max[1] + c.rise * t
    bottom = c.min[1] + (c.rise * t if c.incline is Incline.SHEAR else 0.0)
    return (
        (c.min[0] + tol < x)
        & (x < c.max[0] - tol)
        & (c.min[2] + tol < z)
        & (z < c.max[2] - tol)
        & (bottom + tol < y)
        & (y < top - tol)
    )


def _samples(c: Cuboid, n: int, rng) -> np.ndarray:
    u = rng.random((n, 3))
    x = c.min[0] + u[:, 0] * (c.max[0] - c.min[0])
    z = c.min[2] + u[:, 2] * (c.max[2] - c.min[2])
    t = (x - c.min[0]) / (c.max[0] - c.min[0])
    top = c.max[1] + c.rise * t
    bottom = c.min[1] + (c.rise * t if c.incline is Incline.SHEAR else 0.0)
    return np.stack([x, bottom + u[:, 1] * (top - bottom), z], axis=1)


def test_layout_imports_without_pxr():
    code = (
        "import sys\n"
        "class Block:\n"
        "    def find_spec(self, name, path=None, target=None):\n"
        "        if name == 'pxr' or name.startswith('pxr.'):\n"
        "            raise ImportError('pxr is blocked')\n"
        "sys.meta_path.insert(0, Block())\n"
        "import ionic_usd.temple, ionic_usd.grammar.cuboid\n"
        "ionic_usd.temple.portunus_layout()\n"
        "print('ok')\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "ok"


def test_column_counts(lay):
    assert len(lay.columns_of("free")) == 6
    assert len(lay.columns_of("engaged")) == 8
    # three-quarter columns on the cella's four wall corners
    assert sorted(c.name for c in lay.columns_of("corner")) == [
        "left_3",
        "rear_1",
        "rear_4",
        "right_3",
    ]
    pos = np.array([c.position for c in lay.columns])
    assert len(np.unique(np.round(pos, 6), axis=0)) == 18  # no column placed twice
    # 4 x 7 perimeter: 2 * (4 + 7) - 4 = 18 axes
    assert len({c.name for c in lay.columns}) == 18


def test_free_columns_on_stylobate(lay):
    die = lay.cuboid("die")
    assert_allclose(die.max[1], PODIUM_H)
    assert_allclose([die.max[0] - die.min[0], die.max[2] - die.min[2]], [W, L])
    for c in lay.columns:
        x, y, z = c.position
        assert_allclose(y, lay.stylobate_height)
        r = D / 2
        # the whole lower disc (not only the axis) is on the stylobate
        assert die.min[0] + r < x < die.max[0] - r and die.min[2] + r < z < die.max[2] - r


def test_front_columns_evenly_spaced(lay):
    front = sorted(
        (c for c in lay.columns if c.name.startswith("front")), key=lambda c: c.position[0]
    )
    assert len(front) == 4
    x = np.array([c.position[0] for c in front])
    # documented derivation: 3 s + 2 m = W and 6 s + 2 m = L  =>  s = (L - W) / 3
    s = (L - W) / 3
    assert_allclose(np.diff(x), s)
    assert_allclose(lay.axial_spacing, s)
    margin = (W - 3 * s) / 2
    assert_allclose(x[0], -W / 2 + margin)
    assert_allclose([c.position[2] for c in front], L / 2 - margin)
    assert all(c.kind is ColumnKind.FREE and c.rotation_deg == 0 for c in front)


def test_flank_spacing_equals_front_spacing(lay):
    s = (L - W) / 3
    for sign in (-1, 1):
        z = sorted(c.position[2] for c in lay.columns if np.isclose(c.position[0], sign * 4.4))
        assert len(z) == 7
        assert_allclose(np.diff(z), s)


def test_porch_two_bays_deep(lay):
    free_z = sorted({round(c.position[2], 9) for c in lay.columns_of("free")})
    assert len(free_z) == 2  # front row and one more row
    cella_front = max(c.max[2] for c in lay.cuboids[Layer.CELLA])
    assert_allclose(max(free_z) - cella_front, 2 * lay.axial_spacing)


def test_roof_pitch_from_vertex_heights(lay):
    phi = math.atan(2 / 9)
    assert_allclose(lay.pitch_deg, math.degrees(phi))
    left, right = lay.cuboid("roof_left"), lay.cuboid("roof_right")
    cornice = lay.cuboid("cornice")
    for piece in (left, right):
        p = cuboid_points(piece)
        # every top/bottom edge across the slope climbs tan(phi) per metre towards x = 0
        hi_x, lo_x = p[np.isclose(p[:, 0], piece.max[0])], p[np.isclose(p[:, 0], piece.min[0])]
        dy = np.sort(hi_x[:, 1]) - np.sort(lo_x[:, 1])
        dx = piece.max[0] - piece.min[0]
        expect = math.tan(phi) * dx * (1 if piece is left else -1)
        assert_allclose(dy, expect)
    # the soffit rises cornice width / 9 to the ridge (Vitruvius III.5.12), from its bed
    ridge = cuboid_points(left)[:, 1].max() - left.max[1] + left.min[1]
    width = cornice.max[0] - cornice.min[0]
    assert_allclose(ridge - cornice.max[1], width / 9 + ROOF_BED)
    assert_allclose([left.min[0], right.max[0]], [cornice.min[0], cornice.max[0]])


def test_roof_halves_meet_at_ridge_and_pediment_fills_gable(lay):
    left, right = lay.cuboid("roof_left"), lay.cuboid("roof_right")
    pl, pr = cuboid_points(left), cuboid_points(right)
    ridge_l = np.sort(pl[np.isclose(pl[:, 0], 0.0), 1])
    ridge_r = np.sort(pr[np.isclose(pr[:, 0], 0.0), 1])
    assert_allclose(ridge_l, ridge_r)  # same ridge face, no step
    for ped, slab in ((lay.cuboid("pediment_left"), left), (lay.cuboid("pediment_right"), right)):
        assert ped.incline is Incline.WEDGE
        xs = np.linspace(ped.min[0], ped.max[0], 7)
        assert_allclose(ped.top_at(xs), slab.bottom_at(xs), atol=1e-9)  # touching, no gap
        assert_allclose(ped.min[1], lay.cuboid("cornice").max[1])
        # as wide as the cornice: nothing between the cornice top and the slabs
        cornice = lay.cuboid("cornice")
        assert_allclose(sorted([abs(ped.min[0]), abs(ped.max[0])]), [0.0, cornice.max[0]])
        assert_allclose(
            ped.top_at(cornice.max[0] * np.sign(ped.max[0] + ped.min[0])), cornice.max[1] + ROOF_BED
        )


def test_all_cuboid_meshes_watertight(lay):
    for c in lay.all_cuboids():
        r = inspect_mesh(cuboid_mesh(c))
        assert r.watertight, c.name


def test_cuboids_do_not_overlap(lay, rng):
    cs = lay.all_cuboids()
    for a in cs:
        pts = _samples(a, 400, rng)
        for b in cs:
            if b is not a:
                assert not _inside(b, pts).any(), (a.name, b.name)


def test_columns_clear_of_walls(lay, rng):
    cs = lay.all_cuboids()
    heights = lay.stylobate_height + np.linspace(0.01, H_COL - 0.01, 25)
    for col in lay.columns:
        x, _, z = col.position
        axis = np.array([[x, y, z] for y in heights])
        out = col.facing
        front = axis + 0.45 * out  # the half of the shaft that stands proud of any wall
        if col.kind is ColumnKind.FREE:
            for c in cs:
                assert not _inside(c, axis).any(), (col.name, c.name)
            ang = np.linspace(0, 2 * np.pi, 16, endpoint=False)
            ring = np.concatenate([axis + 0.45 * np.array([np.cos(t), 0, -np.sin(t)]) for t in ang])
            for c in cs:
                assert not _inside(c, ring).any(), (col.name, c.name)
        else:
            for c in cs:
                assert not _inside(c, front).any(), (col.name, c.name)
            # the axis is on the outer face plane of some cella wall, within that face
            on_face = False
            for w in lay.cuboids[Layer.CELLA]:
                for k, (lo, hi) in ((0, (w.min[0], w.max[0])), (2, (w.min[2], w.max[2]))):
                    face = hi if out[k] > 0.5 else lo if out[k] < -0.5 else None
                    if face is None or not np.isclose(col.position[k], face):
                        continue
                    o = 2 - k
                    if w.min[o] - 1e-9 <= col.position[o] <= w.max[o] + 1e-9:
                        on_face = True
            assert on_face, col.name


def test_engaged_face_outward(lay):
    walls = lay.cuboids[Layer.CELLA]
    zc = (min(w.min[2] for w in walls) + max(w.max[2] for w in walls)) / 2
    for col in lay.columns_of("engaged"):
        x, _, z = col.position
        # facing points away from the cella centre, along a wall normal
        assert col.facing @ np.array([x, 0.0, z - zc]) > 0
        assert_allclose(np.sort(np.abs(col.facing)), [0, 0, 1], atol=1e-12)


def test_steps_climb_to_stylobate(lay):
    steps = sorted(
        (c for c in lay.cuboids[Layer.PODIUM] if c.name.startswith("step")), key=lambda c: c.min[1]
    )
    assert len(steps) == 10
    assert steps[0].min[1] == 0.0
    assert_allclose(steps[-1].max[1], PODIUM_H)
    assert_allclose([s.max[1] - s.min[1] for s in steps], PODIUM_H / 10)
    fronts = np.array([s.max[2] for s in steps])
    assert np.all(np.diff(fronts) < 0)
    # the steps lie between the cheek walls
    cheeks = [lay.cuboid("cheek_wall_left"), lay.cuboid("cheek_wall_right")]
    assert_allclose(steps[0].min[0], cheeks[0].max[0])
    assert_allclose(steps[0].max[0], cheeks[1].min[0])


def test_podium_base_footprint(lay):
    pts = np.concatenate([cuboid_points(c) for c in lay.cuboids[Layer.PODIUM]])
    ext = pts.max(axis=0) - pts.min(axis=0)
    assert_allclose([ext[0], ext[2]], [11.87, 25.60])


def test_entablature_rule(lay):
    a, f, c = (lay.cuboid(n) for n in ("architrave", "frieze", "cornice"))
    assert_allclose(a.min[1], PODIUM_H + H_COL)
    ha, hf, hc = (x.max[1] - x.min[1] for x in (a, f, c))
    assert_allclose(ha, H_COL / 12)  # Vitruvius III.5.8 for 25-30 ft columns
    assert_allclose(hf, 1.25 * ha)  # III.5.10, frieze with reliefs
    assert_allclose(hc, ha)
    assert_allclose(c.max[0] - f.max[0], hc)  # III.5.11: projection = height


@pytest.mark.parametrize(
    "hid,check",
    [
        ("roof-pitch-15", lambda L0, L1: np.isclose(L1.pitch_deg, 15.0)),
        (
            "frieze-plain",
            lambda L0, L1: np.isclose(
                L0.cuboid("cornice").max[1] - L1.cuboid("cornice").max[1], 0.5 * H_COL / 12
            ),
        ),
    ],
)
def test_hypotheses_apply(lay, hid, check):
    alt = portunus_layout(apply=[hid])
    assert alt.applied == (hid,)
    assert check(lay, alt)


def test_hypotheses_recorded(lay):
    ids = {h.id for h in lay.hypotheses}
    assert {"flutes-20", "roof-pitch-15", "finish-bare-stone"} <= ids
    for h in lay.hypotheses:
        assert h.sources and h.certainty.value in ("high", "medium", "low")
    with pytest.raises(ParameterError, match="hypothesis"):
        portunus_layout(apply=["no-such-id"])


def test_hypothesis_15_degree_vertex_heights():
    alt = portunus_layout(apply=["roof-pitch-15"])
    left = alt.cuboid("roof_left")
    assert_allclose(left.rise / (left.max[0] - left.min[0]), math.tan(math.radians(15)))


def test_toml_comments_cite_every_number():
    text = (resources.files("ionic_usd") / "data" / "portunus.toml").read_text()
    data = tomllib.loads(text)
    lines = text.splitlines()
    for sec, table in data.items():
        if not isinstance(table, dict):
            continue
        for key, value in table.items():
            if isinstance(value, int | float) and not isinstance(value, bool):
                i = next(i for i, ln in enumerate(lines) if ln.startswith(f"{key} ="))
                # the comment block above the key (or its group) exists
                j = i - 1
                while j >= 0 and not lines[j].startswith("#"):
                    j -= 1
                assert j >= 0 and i - j <= 4, (sec, key)


def test_colonnade_positions():
    p = colonnade_positions((0, 1, 0), (9, 1, 0), 4)
    assert_allclose(p, [[0, 1, 0], [3, 1, 0], [6, 1, 0], [9, 1, 0]])
    assert_allclose(colonnade_positions((1, 2, 3), (5, 5, 5), 1), [[1, 2, 3]])
    with pytest.raises(ParameterError):
        colonnade_positions((0, 0, 0), (1, 0, 0), 0)


def test_column_placement_validation():
    with pytest.raises(ParameterError, match="kind"):
        ColumnPlacement((0, 0, 0), 0.0, "leaning")
    with pytest.raises(ParameterError, match="scale"):
        ColumnPlacement((0, 0, 0), 0.0, "free", scale=0.0)
    assert_allclose(ColumnPlacement((0, 0, 0), 90.0).facing, [1, 0, 0], atol=1e-12)


@pytest.mark.parametrize(
    "kw,key",
    [
        (dict(columns_side=4), "columns.side"),
        (dict(columns_porch_depth=6), "columns.porch_depth"),
        (dict(stylobate_width=12.0, stylobate_length=13.0), "stylobate.width"),
        (dict(podium_height=-1.0), "podium.height"),
        (dict(steps_count=2.5), "steps.count"),
        (dict(podium_base_length=20.0), "podium.base_length"),
    ],
)
def test_params_validation(kw, key):
    with pytest.raises(ParameterError, match=key.replace(".", r"\.")):
        TempleParams(**kw)


# --- TOML -----------------------------------------------------------------------------------


def test_cuboid_toml_round_trip(tmp_path, lay):
    path = tmp_path / "c.toml"
    path.write_text(cuboids_to_toml(lay.cuboids))
    back = load_cuboids_toml(path)
    assert set(back) == set(lay.cuboids)
    for layer, cs in lay.cuboids.items():
        assert [(c.name, c.min, c.max, c.rise, c.incline) for c in back[layer]] == [
            (c.name, c.min, c.max, c.rise, c.incline) for c in cs
        ]


@pytest.mark.parametrize(
    "entry,key",
    [
        ('name = "a"\nlayer = "podium"\nmin = [0, 0, 0]\nmax = [1, 0, 1]', "max.y"),
        ('name = "a"\nlayer = "attic"\nmin = [0, 0, 0]\nmax = [1, 1, 1]', "layer"),
        ('name = "a"\nlayer = "podium"\nmax = [1, 1, 1]', "min"),
        ('name = "a"\nlayer = "podium"\nmin = [0, 0]\nmax = [1, 1, 1]', "min"),
        ('name = "a"\nlayer = "roof"\nmin = [0, 0, 0]\nmax = [1, 1, 1]\ncolour = 3', "colour"),
        ('name = "a"\nlayer = "roof"\nmin = [0, 0, 0]\nmax = [1, 1, 1]\nrise = "x"', "rise"),
    ],
)
def test_cuboid_toml_errors_name_file_entry_key(tmp_path, entry, key):
    path = tmp_path / "bad.toml"
    good = '[[cuboid]]\nname = "ok"\nlayer = "cella"\nmin = [0, 0, 0]\nmax = [1, 1, 1]\n'
    path.write_text(good + "\n[[cuboid]]\n" + entry + "\n")
    with pytest.raises(ParameterError) as ei:
        load_cuboids_toml(path)
    msg = str(ei.value)
    assert "bad.toml" in msg and "#2" in msg and key in msg


def test_temple_toml_unknown_key_and_extra_cuboids(tmp_path):
    src = (resources.files("ionic_usd") / "data" / "portunus.toml").read_text()
    bad = tmp_path / "t.toml"
    bad.write_text(src.replace("[roof]\n", "[roof]\npich = 3\n"))
    with pytest.raises(ParameterError, match=r"roof\.pich"):
        layout_from_toml(bad)
    ok = tmp_path / "altar.toml"
    ok.write_text(
        src + '\n[[cuboid]]\nname = "altar"\nlayer = "podium"\n'
        "min = [-1, 0, 17]\nmax = [1, 1, 18]\n"
    )
    lay = layout_from_toml(ok)
    assert lay.cuboid("altar").max == (1.0, 1.0, 18.0)


def test_build_layout_rejects_duplicate_names():
    with pytest.raises(ParameterError, match="die"):
        build_layout(
            TempleParams(), extra_cuboids={"podium": [Cuboid((0, 0, 0), (1, 1, 1), name="die")]}
        )
