"""The temple composer: counts, instancing, placement, roof pitch, hypotheses, user overrides."""

from __future__ import annotations

import math

import numpy as np
import pytest
from pxr import Gf, Sdf, Usd, UsdGeom

from ionic_usd.cli import main
from ionic_usd.errors import OutputExistsError
from ionic_usd.pipeline.temple import compose_temple
from ionic_usd.temple.layout import portunus_layout
from ionic_usd.usd import validate_stage


def stage_of(report) -> Usd.Stage:
    return Usd.Stage.Open(str(report.root))


def instances(stage) -> list[Usd.Prim]:
    return [p for p in stage.Traverse() if p.IsInstance()]


def test_counts_and_shared_prototypes(portunus_temple):
    stage = stage_of(portunus_temple)
    root = stage.GetDefaultPrim()
    assert root.GetName() == "Temple" and Usd.ModelAPI(root).GetKind() == "assembly"
    inst = instances(stage)
    free = [p for p in inst if p.GetParent().GetName() == "Free"]
    engaged = [p for p in inst if p.GetParent().GetName() == "Engaged"]
    corner = [p for p in inst if p.GetParent().GetName() == "Corner"]
    assert len(free) == 6 and len(engaged) == 8 and len(corner) == 4
    protos = {p.GetPrototype() for p in inst}
    assert len(protos) == 3 == len(stage.GetPrototypes())
    assert {p.GetVariantSets().GetVariantSet("form").GetVariantSelection() for p in free} == {
        "full"
    }
    assert {p.GetVariantSets().GetVariantSet("form").GetVariantSelection() for p in engaged} == {
        "engaged"
    }
    assert {p.GetVariantSets().GetVariantSet("form").GetVariantSelection() for p in corner} == {
        "corner"
    }
    folder = portunus_temple.root.parent
    assert len(list(folder.rglob("IonicColumn.usda"))) == 1
    assert portunus_temple.instances == 18
    assert validate_stage(stage) == []


def test_columns_stand_on_the_stylobate_at_the_documented_spacing(portunus_temple):
    layout = portunus_layout()
    stage = stage_of(portunus_temple)
    cache = UsdGeom.XformCache()
    pos = {
        p.GetName(): np.array(cache.GetLocalToWorldTransform(p).ExtractTranslation())
        for p in instances(stage)
    }
    assert all(abs(v[1] - layout.stylobate_height) < 1e-9 for v in pos.values())
    s = layout.axial_spacing
    assert s == pytest.approx(8.80 / 3)
    front = sorted((v for k, v in pos.items() if k.startswith("front")), key=lambda v: v[0])
    assert len(front) == 4
    assert np.allclose(np.diff([v[0] for v in front]), s)
    # every axis lies within the stylobate footprint
    w, length = layout.params.stylobate_width, layout.params.stylobate_length
    assert all(abs(v[0]) < w / 2 and abs(v[2]) < length / 2 for v in pos.values())
    # world bounds: the column tops reach stylobate + column height
    bbox = UsdGeom.BBoxCache(Usd.TimeCode.Default(), ["default", "render"])
    prim = next(p for p in instances(stage) if p.GetName() == "front_1")
    top = bbox.ComputeWorldBound(prim).ComputeAlignedRange().GetMax()[1]
    assert top == pytest.approx(layout.stylobate_height + 8.22, abs=1e-4)


def test_roof_inclined_by_the_documented_pitch(portunus_temple):
    stage = stage_of(portunus_temple)
    layout = portunus_layout()
    pts = np.array(
        UsdGeom.Mesh(stage.GetPrimAtPath("/Temple/Roof/roof_left")).GetPointsAttr().Get()
    )
    # the slab's top face: the four highest points over x
    top = pts[np.argsort(pts[:, 1])[-4:]]
    low = pts[np.argsort(pts[:, 1])[-8:-4]]
    slope = (top[:, 1].mean() - low[:, 1].mean()) / abs(top[:, 0].mean() - low[:, 0].mean())
    # float32 points (about 1e-6 m at 14 m) over a 5.5 m run: 1e-4 degrees
    assert math.degrees(math.atan(slope)) == pytest.approx(layout.pitch_deg, abs=1e-4)
    assert layout.pitch_deg == pytest.approx(math.degrees(math.atan(2 / 9)))


def composed_values(stage) -> dict[str, tuple]:
    out = {}
    for prim in stage.Traverse():
        vals = []
        for a in prim.GetAttributes():
            if a.GetName() == "extentsHint":  # per combination; tests/test_bounds.py
                continue
            v = a.Get()
            vals.append(
                (
                    a.GetName(),
                    np.asarray(v).tobytes()
                    if v is not None and hasattr(v, "__len__") and not isinstance(v, str)
                    else v,
                )
            )
        rels = tuple((r.GetName(), tuple(r.GetTargets())) for r in prim.GetRelationships())
        sel = tuple(sorted(prim.GetVariantSets().GetAllVariantSelections().items()))
        out[str(prim.GetPath())] = (tuple(vals), rels, sel)
    return out


@pytest.mark.parametrize(
    "hid",
    [
        "flutes-20",
        "roof-pitch-15",
        "frieze-plain",
        "finish-bare-stone",
        "corner-capitals-angled",
        "frieze-garlands",
    ],
)
def test_each_hypothesis_switches_exactly_its_prims(portunus_temple, hid):
    stage = stage_of(portunus_temple)
    root = stage.GetDefaultPrim()
    listing = root.GetCustomData()["ionic_usd"]["hypotheses"][hid.replace("-", "_")]
    # an independent hypothesis is hyp_<id> = alternative; the frieze's two alternatives are
    # values of the one set hyp_frieze (ionic_usd/data/portunus.toml: question = "frieze")
    vset, value = listing["variantSet"], listing["variant"]
    if hid.startswith("frieze-"):
        assert (vset, value) == ("hyp_frieze", hid.replace("-", "_"))
    else:
        assert (vset, value) == ("hyp_" + hid.replace("-", "_"), "alternative")
    assert listing["realised"] is True and root.GetVariantSets().HasVariantSet(vset)
    named = set()
    # the hypothesis' own layer and the detail re-placed for it (<id>.detail.usdc); not the
    # combination layers (<a>+<b>), which apply only with the other hypothesis
    layers = portunus_temple.root.parent / "layers"
    for f in [f for f in layers.iterdir() if f.name.split(".")[0] == hid]:
        layer = Sdf.Layer.FindOrOpen(str(f))
        layer.Traverse(
            Sdf.Path("/Temple"),
            lambda p, la=layer: (
                named.add(str(p))
                if (p.IsPrimPath() and la.GetPrimAtPath(p).customData.get("ionic_usd"))
                else None
            ),
        )
    assert named
    before = composed_values(stage)
    root.GetVariantSets().GetVariantSet(vset).SetVariantSelection(value)
    after = composed_values(stage)
    changed = {p for p in after if before.get(p) != after[p] and not p.startswith("/__")}
    changed.discard("/Temple")  # its variant selection itself

    # prims the default `detail` variant hides show no change; an activated prim
    # brings its descendants along
    def shown(p: str) -> bool:
        prim = stage.GetPrimAtPath(p)
        return prim.IsActive() and UsdGeom.Imageable(prim).ComputeVisibility() != "invisible"

    named = {p for p in named if shown(p)}
    changed = {p for p in changed if shown(p)}
    changed = {p for p in changed if not any(p.startswith(n + "/") for n in named)}
    # instances whose variant selection changed re-point to other prototypes; their
    # descendants are instance proxies and are not traversed
    assert changed == named, hid
    for p in named:
        meta = stage.GetPrimAtPath(p).GetCustomData()["ionic_usd"]["hypotheses"][
            hid.replace("-", "_")
        ]
        assert meta["id"] == hid and meta["certainty"] in ("high", "medium", "low")
        assert len(meta["sources"]) >= 1
    assert validate_stage(stage) == []


def test_hypotheses_are_listed(portunus_temple):
    stage = stage_of(portunus_temple)
    listing = stage.GetDefaultPrim().GetCustomData()["ionic_usd"]["hypotheses"]
    assert listing["corner_capitals_angled"]["realised"] is True
    assert listing["roof_pitch_15"]["realised"] is True


def test_angle_capitals_on_the_four_corners(portunus_temple):
    """The angle-capital hypothesis selects the angle capital on the colonnade's corners and
    turns each so both volute faces (local +Z, +X) face outward."""
    stage = stage_of(portunus_temple)
    root = stage.GetDefaultPrim()
    root.GetVariantSets().GetVariantSet("hyp_corner_capitals_angled").SetVariantSelection(
        "alternative"
    )
    angled = {
        p.GetName(): p
        for p in instances(stage)
        if p.GetVariantSets().GetVariantSet("capital").GetVariantSelection() == "angle"
    }
    assert sorted(angled) == ["front_1", "front_4", "rear_1", "rear_4"]
    for name, prim in angled.items():
        m = np.array(UsdGeom.Xformable(prim).ComputeLocalToWorldTransform(0))[:3, :3]
        local_z, local_x = m[2], m[0]  # row vectors: images of the local axes
        pos = np.array(UsdGeom.Xformable(prim).ComputeLocalToWorldTransform(0))[3, :3]
        out = {(int(np.sign(pos[0])), 0, 0), (0, 0, int(np.sign(pos[2])))}
        assert {
            tuple(np.round(local_z).astype(int)),
            tuple(np.round(local_x).astype(int)),
        } == out, name
    assert validate_stage(stage) == []


def test_user_overrides_survive_regeneration(tmp_path):
    folder = tmp_path / "T"
    layout = portunus_layout()
    compose_temple(folder, layout, texture_size=16)
    user = Sdf.Layer.FindOrOpen(str(folder / "overrides.usda"))
    spec = Sdf.CreatePrimInLayer(user, "/Temple/Colonnade/Free/front_1")
    spec.specifier = Sdf.SpecifierOver
    a = Sdf.AttributeSpec(spec, "xformOp:rotateXYZ", Sdf.ValueTypeNames.Float3)
    a.default = Gf.Vec3f(0, 33, 0)
    spec.customData = {"note": "my reading of the plan"}
    user.Save()
    before = (folder / "overrides.usda").read_bytes()
    with pytest.raises(OutputExistsError):
        compose_temple(folder, layout, texture_size=16)
    compose_temple(folder, layout, texture_size=16, force=True, rebuild=True)
    assert (folder / "overrides.usda").read_bytes() == before
    stage = Usd.Stage.Open(str(folder / "Temple.usda"))
    prim = stage.GetPrimAtPath("/Temple/Colonnade/Free/front_1")
    assert prim.GetAttribute("xformOp:rotateXYZ").Get() == Gf.Vec3f(0, 33, 0)
    xf = UsdGeom.Xformable(prim).ComputeLocalToWorldTransform(Usd.TimeCode.Default())
    assert Gf.IsClose(
        xf.ExtractRotation().GetAxis() * xf.ExtractRotation().GetAngle(), Gf.Vec3d(0, 33, 0), 1e-6
    )


def test_cli_temple_errors(tmp_path, capsys):
    assert main(["temple", "--layout", "parthenon", "-o", str(tmp_path / "x")]) == 2
    err = capsys.readouterr().err
    assert "portunus" in err and not (tmp_path / "x").exists()
    cfg = tmp_path / "t.toml"
    cfg.write_text("[podium]\nheight = -1\n")
    assert main(["temple", "--config", str(cfg), "-o", str(tmp_path / "y")]) == 2
    assert "podium" in capsys.readouterr().err and not (tmp_path / "y").exists()


def test_shipped_hypothesis_layers_are_up_to_date(portunus_temple):
    from pathlib import Path

    from ionic_usd.usd.temple import hypothesis_layers

    shipped = Path(__file__).resolve().parent.parent / "layers" / "portunus"
    layers = {k: v for k, v in hypothesis_layers(portunus_layout()).items() if v is not None}
    assert sorted(p.stem for p in shipped.glob("*.usda")) == sorted(layers)
    for hid, layer in layers.items():
        fresh = layer.ExportToString()
        assert Sdf.Layer.FindOrOpen(str(shipped / f"{hid}.usda")).ExportToString() == fresh, (
            f"layers/portunus/{hid}.usda is stale: run python tools/make_layers.py"
        )
        written = portunus_temple.root.parent / "layers" / f"{hid}.usda"
        assert Sdf.Layer.FindOrOpen(str(written)).ExportToString() == fresh
