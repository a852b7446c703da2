"""Headless preview renderer: real renders on the EGL context, checked on the pictures."""

from __future__ import annotations

import importlib.util
import sys

import numpy as np
import OpenImageIO as oiio
import pytest
from pxr import Gf, Sdf, Usd, UsdGeom, UsdShade

from ionic_usd.errors import OutputExistsError, ParameterError, UsdAuthoringError
from ionic_usd.preview import PreviewUnavailableError, create_context, render_preview

# Only a missing moderngl skips; a moderngl that cannot make an EGL context fails loudly.
needs_gl = pytest.mark.skipif(
    importlib.util.find_spec("moderngl") is None,
    reason="moderngl is not installed (pip install 'ionic_usd[preview]')",
)

CUBE_POINTS = [
    (-0.5, 0, -0.5),
    (0.5, 0, -0.5),
    (0.5, 0, 0.5),
    (-0.5, 0, 0.5),
    (-0.5, 1, -0.5),
    (0.5, 1, -0.5),
    (0.5, 1, 0.5),
    (-0.5, 1, 0.5),
]
CUBE_FACES = [0, 3, 2, 1, 4, 5, 6, 7, 0, 1, 5, 4, 1, 2, 6, 5, 2, 3, 7, 6, 3, 0, 4, 7]
RED = (0.8, 0.03, 0.03)


def _cube(stage: Usd.Stage, path: str, colour=RED) -> UsdGeom.Mesh:
    mesh = UsdGeom.Mesh.Define(stage, path)
    mesh.CreatePointsAttr(CUBE_POINTS)
    mesh.CreateFaceVertexCountsAttr([4] * 6)
    mesh.CreateFaceVertexIndicesAttr(CUBE_FACES)
    mesh.CreateDisplayColorPrimvar().Set([colour])
    return mesh


def _pyramid(stage: Usd.Stage, path: str) -> UsdGeom.Mesh:
    """A square pyramid: 1 quad + 4 triangles = 6 triangles after fan triangulation."""
    mesh = UsdGeom.Mesh.Define(stage, path)
    mesh.CreatePointsAttr(
        [(-0.4, 0, -0.4), (0.4, 0, -0.4), (0.4, 0, 0.4), (-0.4, 0, 0.4), (0, 1.5, 0)]
    )
    mesh.CreateFaceVertexCountsAttr([4, 3, 3, 3, 3])
    mesh.CreateFaceVertexIndicesAttr([0, 1, 2, 3, 0, 4, 1, 1, 4, 2, 2, 4, 3, 3, 4, 0])
    return mesh


def _new_stage(path, up: str = "Y") -> Usd.Stage:
    stage = Usd.Stage.CreateNew(str(path))
    UsdGeom.SetStageUpAxis(stage, up)
    UsdGeom.SetStageMetersPerUnit(stage, 1.0)
    stage.SetDefaultPrim(UsdGeom.Xform.Define(stage, "/World").GetPrim())
    return stage


def make_scene(tmp_path, *, instanceable: bool = True, plain_edit=None):
    """cube.usda (one cube mesh) referenced twice at x = ±1.5, plus a plain pyramid mesh."""
    cube = Usd.Stage.CreateNew(str(tmp_path / "cube.usda"))
    UsdGeom.SetStageUpAxis(cube, "Y")
    cube.SetDefaultPrim(UsdGeom.Xform.Define(cube, "/Cube").GetPrim())
    _cube(cube, "/Cube/Geom")
    cube.GetRootLayer().Save()
    stage = _new_stage(tmp_path / "scene.usda")
    for i, x in enumerate((-1.5, 1.5)):
        xf = UsdGeom.Xform.Define(stage, f"/World/Cube{i}")
        xf.GetPrim().GetReferences().AddReference("./cube.usda")
        xf.GetPrim().SetInstanceable(instanceable)
        xf.AddTranslateOp().Set(Gf.Vec3d(x, 0, 0))
    plain = _pyramid(stage, "/World/Plain")
    if plain_edit is not None:
        plain_edit(plain)
    stage.GetRootLayer().Save()
    return tmp_path / "scene.usda"


def read_png(path) -> np.ndarray:
    inp = oiio.ImageInput.open(str(path))
    assert inp is not None, oiio.geterror()
    px = inp.read_image(oiio.UINT8)
    inp.close()
    return np.asarray(px)


def object_mask(px: np.ndarray, tol: int = 10) -> np.ndarray:
    """Pixels unlike their row's median: with ground=False the background is a vertical
    gradient, constant along each row, so this finds the geometry wherever it covers less
    than half of a row."""
    med = np.median(px.astype(np.int32), axis=1, keepdims=True)
    return np.abs(px.astype(np.int32) - med).max(axis=2) > tol


def red_mask(px: np.ndarray) -> np.ndarray:
    p = px.astype(np.int32)
    return (p[..., 0] - np.maximum(p[..., 1], p[..., 2])) > 60


# -- pictures ----------------------------------------------------------------------------------
@needs_gl
def test_instanced_scene(tmp_path):
    out = tmp_path / "pic.png"
    stats = render_preview(make_scene(tmp_path), out, width=320, height=240)
    px = read_png(out)
    assert px.shape == (240, 320, 3)
    assert not [f for f in tmp_path.iterdir() if f.name.startswith(".")]  # no temporary left
    assert px.std() > 10  # not blank
    # both instances drawn: red pixels in the left half (x = -1.5) and the right half (+1.5)
    red = red_mask(px)
    assert red[:, :160].sum() > 300 and red[:, 160:].sum() > 300
    # the red cubes differ from the background (the top-left corner is sky)
    assert np.abs(px[red].mean(axis=0) - px[0, 0].astype(float)).max() > 60
    assert stats.prototypes == 1
    assert stats.instances == 2
    assert stats.meshes == 2  # the prototype's cube uploaded once + the plain pyramid
    assert stats.triangles == 2 * 12 + 6
    assert (stats.width, stats.height) == (320, 240)
    assert stats.seconds >= stats.render_seconds > 0


@needs_gl
def test_instancing_does_not_change_the_picture(tmp_path):
    (tmp_path / "a").mkdir()
    (tmp_path / "b").mkdir()
    kw = dict(width=200, height=150, samples=0)
    inst = render_preview(make_scene(tmp_path / "a"), tmp_path / "a.png", **kw)
    flat = render_preview(make_scene(tmp_path / "b", instanceable=False), tmp_path / "b.png", **kw)
    assert (inst.instances, flat.instances) == (2, 0)
    # the reader keys meshes by content: the two equal cubes are uploaded once either way
    assert (inst.meshes, flat.meshes) == (2, 2)
    assert inst.triangles == flat.triangles
    diff = np.abs(read_png(tmp_path / "a.png").astype(int) - read_png(tmp_path / "b.png"))
    assert diff.mean() < 0.5


@needs_gl
@pytest.mark.parametrize(
    "edit",
    [
        lambda m: m.CreateVisibilityAttr(UsdGeom.Tokens.invisible),
        lambda m: m.CreatePurposeAttr(UsdGeom.Tokens.guide),
        lambda m: m.CreatePurposeAttr(UsdGeom.Tokens.proxy),
        lambda m: m.GetPrim().SetActive(False),
    ],
    ids=["invisible", "guide", "proxy", "inactive"],
)
def test_hidden_meshes_are_skipped(tmp_path, edit):
    stats = render_preview(
        make_scene(tmp_path, plain_edit=edit), tmp_path / "p.png", width=64, height=48, samples=0
    )
    assert stats.triangles == 2 * 12
    assert stats.meshes == 1


@needs_gl
def test_shaft_appears_tall(tmp_path):
    from ionic_usd.column.shaft import build_shaft
    from ionic_usd.usd import write_meshes

    path = write_meshes(tmp_path / "shaft.usdc", {"Shaft": build_shaft()})
    out = tmp_path / "shaft.png"
    stats = render_preview(path, out, width=400, height=300, camera="front", ground=False)
    mask = object_mask(read_png(out))
    rows, cols = np.nonzero(mask)
    assert mask.sum() > 2000
    height, width = np.ptp(rows) + 1, np.ptp(cols) + 1
    # Portunus shaft: 7.14 m tall, 0.95 m across; a 40° view framing it fills most of the height
    assert height > 0.7 * 300
    assert height > 4 * width
    assert abs(cols.mean() - 200) < 20  # centred
    assert stats.instances == 0 and stats.meshes == 1


@needs_gl
def test_z_up_stage_is_rotated(tmp_path):
    stage = _new_stage(tmp_path / "z.usda", up="Z")
    box = _cube(stage, "/World/Box")
    # 4 units tall along +Z, the stage's up axis (y <-> z keeps the faces, mirrors the winding)
    box.GetPointsAttr().Set([(0.5 * x, 0.5 * z, 4.0 * y) for x, y, z in CUBE_POINTS])
    stage.GetRootLayer().Save()
    out = tmp_path / "z.png"
    render_preview(tmp_path / "z.usda", out, width=240, height=240, camera="front", ground=False)
    rows, cols = np.nonzero(object_mask(read_png(out)))
    assert np.ptp(rows) > 3 * np.ptp(cols)


@needs_gl
def test_lod_variant_selection(tmp_path):
    stage = _new_stage(tmp_path / "lod.usda")
    prim = stage.GetPrimAtPath("/World")
    vset = prim.GetVariantSets().AddVariantSet("lod")
    for name, maker in (("low", _pyramid), ("high", _cube)):
        vset.AddVariant(name)
        vset.SetVariantSelection(name)
        with vset.GetVariantEditContext():
            maker(stage, f"/World/{name}")
    vset.SetVariantSelection("low")
    stage.GetRootLayer().Save()
    kw = dict(width=64, height=48, samples=0, force=True)
    out = tmp_path / "l.png"
    assert render_preview(tmp_path / "lod.usda", out, **kw).triangles == 6
    assert render_preview(tmp_path / "lod.usda", out, lod="high", **kw).triangles == 12
    with pytest.raises(ParameterError, match="high, low"):
        render_preview(tmp_path / "lod.usda", out, lod="ultra", **kw)
    with pytest.raises(ParameterError, match="no 'lod' variant set"):
        render_preview(make_scene(tmp_path), out, lod="high", **kw)


@needs_gl
@pytest.mark.parametrize("textured", [False, True])
def test_preview_surface_colour(tmp_path, textured):
    stage = _new_stage(tmp_path / "m.usda")
    mesh = _cube(stage, "/World/Box", colour=RED)  # the material must win over displayColor
    mat = UsdShade.Material.Define(stage, "/World/Mat")
    surf = UsdShade.Shader.Define(stage, "/World/Mat/Surface")
    surf.CreateIdAttr("UsdPreviewSurface")
    diffuse = surf.CreateInput("diffuseColor", Sdf.ValueTypeNames.Color3f)
    if textured:  # a blue image: the renderer uses its mean colour
        img = np.zeros((8, 8, 3), np.uint8)
        img[..., 2] = 230
        out = oiio.ImageOutput.create(str(tmp_path / "blue.png"))
        out.open(str(tmp_path / "blue.png"), oiio.ImageSpec(8, 8, 3, oiio.UINT8))
        out.write_image(img)
        out.close()
        tex = UsdShade.Shader.Define(stage, "/World/Mat/Tex")
        tex.CreateIdAttr("UsdUVTexture")
        tex.CreateInput("file", Sdf.ValueTypeNames.Asset).Set("./blue.png")
        diffuse.ConnectToSource(tex.CreateOutput("rgb", Sdf.ValueTypeNames.Float3))
        want = 2
    else:
        diffuse.Set(Gf.Vec3f(0.05, 0.7, 0.05))
        want = 1
    mat.CreateSurfaceOutput().ConnectToSource(surf.ConnectableAPI(), "surface")
    UsdShade.MaterialBindingAPI.Apply(mesh.GetPrim()).Bind(mat)
    stage.GetRootLayer().Save()
    png = tmp_path / "m.png"
    render_preview(tmp_path / "m.usda", png, width=120, height=90, ground=False)
    px = read_png(png).astype(int)
    obj = px[object_mask(px.astype(np.uint8))]
    assert len(obj) > 500
    others = [c for c in range(3) if c != want]
    dominant = obj[:, want] - obj[:, others].max(axis=1)
    assert np.median(dominant) > 40


@needs_gl
def test_point_instancer(tmp_path):
    stage = _new_stage(tmp_path / "pi.usda")
    pi = UsdGeom.PointInstancer.Define(stage, "/World/Scatter")
    _cube(stage, "/World/Scatter/Protos/Cube")
    pi.CreatePrototypesRel().SetTargets(["/World/Scatter/Protos/Cube"])
    pi.CreatePositionsAttr([(-2, 0, 0), (0, 0, 0), (2, 0, 0)])
    pi.CreateProtoIndicesAttr([0, 0, 0])
    stage.GetRootLayer().Save()
    out = tmp_path / "pi.png"
    stats = render_preview(
        tmp_path / "pi.usda", out, width=240, height=120, camera="front", ground=False
    )
    assert (stats.meshes, stats.prototypes, stats.instances) == (1, 1, 3)
    assert stats.triangles == 36
    red = red_mask(read_png(out))
    cols = np.flatnonzero(red.any(axis=0))
    assert len(np.flatnonzero(np.diff(cols) > 1)) == 2  # three separate red blobs


# -- errors ------------------------------------------------------------------------------------
def test_missing_file(tmp_path):
    with pytest.raises(ParameterError, match="existing USD file"):
        render_preview(tmp_path / "nope.usda", tmp_path / "x.png")


def test_unreadable_stage(tmp_path):
    bad = tmp_path / "bad.usda"
    bad.write_text('#usda 1.0\ndef Xform "A" {{{ garbage\n')
    with pytest.raises(UsdAuthoringError, match="cannot open"):
        render_preview(bad, tmp_path / "x.png")


@pytest.mark.parametrize(
    "kwargs, name",
    [
        ({"camera": "top"}, "camera"),
        ({"width": 0}, "width"),
        ({"samples": -1}, "samples"),
        ({"background": (1, 2, 3)}, "background"),
    ],
    ids=["camera", "width", "samples", "background"],
)
def test_bad_arguments(tmp_path, kwargs, name):
    with pytest.raises(ParameterError, match=name):
        render_preview(make_scene(tmp_path), tmp_path / "x.png", **kwargs)


def test_output_rules(tmp_path):
    scene = make_scene(tmp_path)
    with pytest.raises(ParameterError, match=r"\.png"):
        render_preview(scene, tmp_path / "x.jpg")
    (tmp_path / "x.png").write_bytes(b"old")
    with pytest.raises(OutputExistsError):
        render_preview(scene, tmp_path / "x.png")
    assert (tmp_path / "x.png").read_bytes() == b"old"


def test_no_moderngl_names_the_extra(monkeypatch):
    monkeypatch.setitem(sys.modules, "moderngl", None)  # makes `import moderngl` fail
    with pytest.raises(PreviewUnavailableError, match=r"pip install 'ionic_usd\[preview\]'"):
        create_context()


@needs_gl
def test_no_egl_names_the_packages(monkeypatch):
    import moderngl

    def fail(**kwargs):
        raise Exception("libEGL.so: cannot open shared object file")

    monkeypatch.setattr(moderngl, "create_standalone_context", fail)
    with pytest.raises(PreviewUnavailableError, match="apt-get install libegl1"):
        create_context()


# -- one reader: preview draws what export writes ----------------------------------------------
def _hypothesis_selection(root) -> dict[str, str]:
    from ionic_usd.usd.city import temple_variant_sets

    sets = temple_variant_sets(root)
    return {
        name: "alternative"
        for name in sorted(sets)
        if name.startswith("hyp_") and "alternative" in sets[name]
    }


@needs_gl
@pytest.mark.parametrize("which", ["authored", "hypotheses + engaged"])
def test_preview_and_export_read_the_same_meshes(tiny_temple, tmp_path, which):
    import trimesh

    from ionic_usd.export import export_scene
    from ionic_usd.preview.scene import draw_items
    from ionic_usd.usd.reader import read_scene

    sel = (
        {}
        if which == "authored"
        else {**_hypothesis_selection(tiny_temple.root), "form": "engaged"}
    )
    assert which == "authored" or len(sel) >= 3
    res = export_scene(tiny_temple.root, tmp_path / "t.glb", variants=sel, gpu_instancing=False)
    glb = trimesh.load(tmp_path / "t.glb", force="scene", process=False).to_geometry()
    stats = render_preview(
        tiny_temple.root,
        tmp_path / "t.png",
        width=64,
        height=48,
        samples=0,
        ground=False,
        variants=sel,
    )
    assert stats.triangles == res.report.triangles_drawn == len(glb.faces)
    # the preview's draw lists, placed: the same world bounds as the exported file's
    items = draw_items(read_scene(tiny_temple.root, variants=sel, draw_modes=True))
    pts = np.concatenate(
        [
            np.einsum(
                "vi,nij->nvj", np.c_[d.vertices[:, :3], np.ones(len(d.vertices))], d.placements
            )[..., :3].reshape(-1, 3)
            for d in items
        ]
    )
    np.testing.assert_allclose(pts.min(axis=0), glb.bounds[0], atol=1e-4)
    np.testing.assert_allclose(pts.max(axis=0), glb.bounds[1], atol=1e-4)
    if sel:  # the selection changed what is drawn
        plain = draw_items(read_scene(tiny_temple.root, draw_modes=True))
        assert {d.key for d in plain} != {d.key for d in items}


# Hydra's card box, transcribed from OpenUSD pxr/usdImaging/usdImaging/drawModeAdapter.cpp
# (UsdImagingDrawModeAdapter::_GenerateCardsGeometry: the four corners of each face, in terms
# of the bound's min "0" / max "1" per axis; _GetUVsForQuad + _GenerateTextureCoordinates: their
# uv). drawModeStandin.cpp (_CardsDataCache::_CardsData::_ComputePoints/_ComputeUVs, the scene
# index path) builds the same quads and uvs. UsdUVTexture's st (0, 0) is the image's bottom left.
_HYDRA_CORNERS = {
    "XPos": ["111", "101", "100", "110"],
    "XNeg": ["001", "011", "010", "000"],
    "YPos": ["011", "111", "110", "010"],
    "YNeg": ["101", "001", "000", "100"],
    "ZPos": ["111", "011", "001", "101"],
    "ZNeg": ["010", "110", "100", "000"],
}  # x, y, z digits; cardGeometry box (cross puts the face's own axis at the middle)


def _hydra_uv(flip_u: bool, flip_v: bool) -> np.ndarray:
    """_GetUVsForQuad(flipU, flipV)."""
    u0, u1 = (1, 0) if flip_u else (0, 1)
    v0, v1 = (1, 0) if flip_v else (0, 1)
    return np.array([(u1, v1), (u0, v1), (u0, v0), (u1, v0)], dtype=float)


def _hydra_face_uvs(has: set[str]) -> dict[str, np.ndarray]:
    """_GenerateTextureCoordinates for the faces drawn, given the faces with a texture."""
    out = {}
    for a in "XY":
        out[a + "Pos"] = _hydra_uv(a + "Pos" not in has, False)
        out[a + "Neg"] = _hydra_uv(a + "Neg" not in has, False)
    out["ZPos"] = _hydra_uv(False, "ZPos" not in has)
    out["ZNeg"] = _hydra_uv(True, "ZNeg" in has)
    return out


def _affine_st(face: str, corners: np.ndarray, uv: np.ndarray, p: np.ndarray) -> np.ndarray:
    """st of the point p (3,) projected on a quad with corners (4, 3) and their uv (4, 2)."""
    keep = [i for i in range(3) if i != "XYZ".index(face[0])]
    a = np.c_[corners[:, keep], np.ones(4)]
    coef, *_ = np.linalg.lstsq(a, uv, rcond=None)
    np.testing.assert_allclose(a @ coef, uv, atol=1e-9)  # affine on the quad (a rectangle)
    return np.r_[p[keep], 1.0] @ coef


@needs_gl
def test_card_images_follow_hydras_uv_mapping(tmp_path):
    """Bake the cards of a bound holding one small marker box near a corner (+X, +Y, +Z by
    different amounts, so a swapped or flipped axis moves it) and find the marker in each image
    where Hydra's quad and uv put it; our reader's quads map it to the same st."""
    from numpy.testing import assert_allclose as close

    from ionic_usd.preview import bake_cards
    from ionic_usd.usd.draw_mode import author_cards, card_bbox_cache, card_faces

    lo, hi = np.array([-1.0, -1.5, -2.0]), np.array([1.0, 1.5, 2.0])
    centre = np.array([0.35, 0.7, 1.1])
    stage = _new_stage(tmp_path / "m.usda")
    model = stage.GetPrimAtPath("/World")
    Usd.ModelAPI(model).SetKind("component")
    UsdGeom.ModelAPI.Apply(model).SetExtentsHint([Gf.Vec3f(*lo), Gf.Vec3f(*hi)])
    mesh = UsdGeom.Mesh.Define(stage, "/World/Marker")
    mesh.CreatePointsAttr(
        [
            tuple(centre + 0.15 * (np.array(p) * 2 - (1, 1, 1)))
            for p in [(c[0] + 0.5, c[1], c[2] + 0.5) for c in CUBE_POINTS]
        ]
    )
    mesh.CreateFaceVertexCountsAttr([4] * 6)
    mesh.CreateFaceVertexIndicesAttr(CUBE_FACES)
    mesh.CreateDisplayColorPrimvar().Set([RED])
    stage.Save()
    bake = bake_cards(tmp_path / "m.usda", tmp_path / "cards", (lo, hi), size=160, samples=0)

    box = np.stack([lo, hi])
    hydra_uv = _hydra_face_uvs(set(_HYDRA_CORNERS))
    for face, digits in _HYDRA_CORNERS.items():
        corners = np.array([[box[int(d), i] for i, d in enumerate(ds)] for ds in digits])
        s, t = _affine_st(face, corners, hydra_uv[face], centre)
        inp = oiio.ImageInput.open(str(bake.files[face]))
        px = np.asarray(inp.read_image(oiio.UINT8))
        inp.close()
        h, w = px.shape[:2]
        # the image spans the face: its aspect is the quad's length along s over that along t
        uv = hydra_uv[face]
        at = {tuple(q): corners[i] for i, q in enumerate(uv)}
        span_s = np.linalg.norm(at[(1, 0)] - at[(0, 0)])
        span_t = np.linalg.norm(at[(0, 1)] - at[(0, 0)])
        assert abs(w / h - span_s / span_t) < 0.05, face
        rows, cols = np.nonzero(px[..., 3] >= 128)
        assert len(rows) > 20, face
        # pixel centres: column (s * w - 0.5), row from the top ((1 - t) * h - 0.5)
        assert abs(cols.mean() - (s * w - 0.5)) < 1.5, (face, cols.mean(), s * w)
        assert abs(rows.mean() - ((1 - t) * h - 0.5)) < 1.5, (face, rows.mean(), (1 - t) * h)

    # our reader's quads give the marker the same st, with all six images and with only the
    # Pos ones (the Neg faces borrow them, as Hydra's flipped uvs say)
    for authored in (list(_HYDRA_CORNERS), ["XPos", "YPos", "ZPos"]):
        layer = Sdf.Layer.OpenAsAnonymous(str(tmp_path / "m.usda"))
        author_cards(layer.GetPrimAtPath("/World"), {f: str(bake.files[f]) for f in authored})
        stage = Usd.Stage.Open(layer)
        ours = {f.name: f for f in card_faces(stage.GetPrimAtPath("/World"), card_bbox_cache())}
        assert sorted(ours) == sorted(_HYDRA_CORNERS)
        hydra_uv = _hydra_face_uvs(set(authored))
        for face, digits in _HYDRA_CORNERS.items():
            corners = np.array([[box[int(d), i] for i, d in enumerate(ds)] for ds in digits])
            expect = _affine_st(face, corners, hydra_uv[face], centre)
            got = _affine_st(face, ours[face].points, ours[face].st, centre)
            close(got, expect, atol=1e-9, err_msg=face)
            src = face if face in authored else face[0] + "Pos"
            assert ours[face].texture == str(bake.files[src])
