"""UsdPreviewSurface materials reading ``st`` through UsdUVTexture (DESIGN convention 11)."""

from __future__ import annotations

from pxr import Gf, Sdf, Usd, UsdShade

from ionic_usd.blueprint.materials import TILE_METRES, MaterialTextures

__all__ = [
    "FALLBACKS",
    "TILE_METRES",
    "MaterialTextures",
    "author_preview_material",
    "bind_material",
    "bind_material_spec",
    "stone_material",
]

# UsdUVTexture ``inputs:fallback`` per map, in the map's own encoding: a mid stone colour, a
# matte roughness, and the flat tangent-space normal (0.5, 0.5, 1) that decodes to (0, 0, 1)
FALLBACKS = {
    "BaseColor": Gf.Vec4f(0.62, 0.58, 0.52, 1.0),
    "Roughness": Gf.Vec4f(0.8, 0.8, 0.8, 1.0),
    "Normal": Gf.Vec4f(0.5, 0.5, 1.0, 1.0),
}


def author_preview_material(
    stage: Usd.Stage,
    path: str,
    textures: MaterialTextures,
    *,
    metallic: float = 0.0,
    specular_tint: tuple[float, float, float] | None = None,
    st_scale: float | None = None,
) -> UsdShade.Material:
    """Define a Material with a UsdPreviewSurface fed by three UsdUVTexture nodes.

    Parameters
    ----------
    stage : the stage whose edit target receives the material
    path : material prim path, e.g. ``/IonicColumn/Materials/Travertine``
    textures : the maps, as ``./``-relative asset paths from the authoring layer
    st_scale : repeat the (tileable) textures this many times per unit of ``st`` through a
        UsdTransform2d node; None reads ``st`` directly
    """
    mat = UsdShade.Material.Define(stage, path)
    surf = UsdShade.Shader.Define(stage, f"{path}/PreviewSurface")
    surf.CreateIdAttr("UsdPreviewSurface")
    surf.CreateInput("metallic", Sdf.ValueTypeNames.Float).Set(float(metallic))
    surf.CreateInput("useSpecularWorkflow", Sdf.ValueTypeNames.Int).Set(0)
    mat.CreateSurfaceOutput().ConnectToSource(surf.ConnectableAPI(), "surface")

    reader = UsdShade.Shader.Define(stage, f"{path}/StReader")
    reader.CreateIdAttr("UsdPrimvarReader_float2")
    reader.CreateInput("varname", Sdf.ValueTypeNames.String).Set("st")
    st_out = reader.CreateOutput("result", Sdf.ValueTypeNames.Float2)
    if st_scale is not None:
        xf = UsdShade.Shader.Define(stage, f"{path}/StTransform")
        xf.CreateIdAttr("UsdTransform2d")
        xf.CreateInput("in", Sdf.ValueTypeNames.Float2).ConnectToSource(st_out)
        xf.CreateInput("scale", Sdf.ValueTypeNames.Float2).Set(Gf.Vec2f(st_scale, st_scale))
        st_out = xf.CreateOutput("result", Sdf.ValueTypeNames.Float2)

    def texture(name: str, file: str, colour_space: str, out_name: str, out_type):
        tex = UsdShade.Shader.Define(stage, f"{path}/{name}")
        tex.CreateIdAttr("UsdUVTexture")
        tex.CreateInput("file", Sdf.ValueTypeNames.Asset).Set(Sdf.AssetPath(file))
        # what a renderer shows when the map is missing (UsdUVTexture's default is black)
        tex.CreateInput("fallback", Sdf.ValueTypeNames.Float4).Set(FALLBACKS[name])
        tex.CreateInput("st", Sdf.ValueTypeNames.Float2).ConnectToSource(st_out)
        tex.CreateInput("sourceColorSpace", Sdf.ValueTypeNames.Token).Set(colour_space)
        tex.CreateInput("wrapS", Sdf.ValueTypeNames.Token).Set("repeat")
        tex.CreateInput("wrapT", Sdf.ValueTypeNames.Token).Set("repeat")
        return tex, tex.CreateOutput(out_name, out_type)

    _, rgb = texture("BaseColor", textures.basecolor, "sRGB", "rgb", Sdf.ValueTypeNames.Float3)
    surf.CreateInput("diffuseColor", Sdf.ValueTypeNames.Color3f).ConnectToSource(rgb)
    _, r = texture("Roughness", textures.roughness, "raw", "r", Sdf.ValueTypeNames.Float)
    surf.CreateInput("roughness", Sdf.ValueTypeNames.Float).ConnectToSource(r)
    ntex, n = texture("Normal", textures.normal, "raw", "rgb", Sdf.ValueTypeNames.Float3)
    # 8-bit normal maps store n * 0.5 + 0.5; UsdUVTexture's scale/bias decode them
    ntex.CreateInput("scale", Sdf.ValueTypeNames.Float4).Set(Gf.Vec4f(2.0, 2.0, 2.0, 1.0))
    ntex.CreateInput("bias", Sdf.ValueTypeNames.Float4).Set(Gf.Vec4f(-1.0, -1.0, -1.0, 0.0))
    surf.CreateInput("normal", Sdf.ValueTypeNames.Normal3f).ConnectToSource(n)
    if specular_tint is not None:
        surf.CreateInput("specularColor", Sdf.ValueTypeNames.Color3f).Set(Gf.Vec3f(*specular_tint))
    return mat


def bind_material(prim: Usd.Prim, material: UsdShade.Material | str) -> None:
    """Apply MaterialBindingAPI to ``prim`` and bind ``material`` (a Material or its path).

    A path binding works across layers: the material may live in another sublayer.
    """
    api = UsdShade.MaterialBindingAPI.Apply(prim)
    if isinstance(material, str):
        rel = api.GetDirectBindingRel()
        if not rel:
            rel = prim.CreateRelationship("material:binding", custom=False)
        rel.SetTargets([Sdf.Path(material)])
    else:
        api.Bind(material)


def bind_material_spec(spec: Sdf.PrimSpec, material: str, *, stronger: bool = False) -> None:
    """The Sdf form of :func:`bind_material`: apply MaterialBindingAPI to a prim spec and set
    its direct binding to the material path (no stage needed, nothing resolved).

    ``stronger`` authors ``bindMaterialAs = strongerThanDescendants``: the binding wins over
    the bindings of every descendant (a column's, referenced from its asset)."""
    spec.SetInfo("apiSchemas", Sdf.TokenListOp.Create(prependedItems=["MaterialBindingAPI"]))
    rel = spec.relationships.get("material:binding") or Sdf.RelationshipSpec(
        spec, "material:binding", custom=False
    )
    rel.targetPathList.explicitItems = [Sdf.Path(material)]
    if stronger:
        rel.SetInfo("bindMaterialAs", UsdShade.Tokens.strongerThanDescendants)


def stone_material(
    stage: Usd.Stage,
    path: str,
    style: str,
    *,
    st_scale: float | None = None,
    specular_tint: tuple[float, float, float] | None = None,
) -> UsdShade.Material:
    """A material reading a stone style's maps from ``./Textures/<style>_<map>.png`` (written by
    :func:`copy_stone_textures`) — the one way every ionic_usd material names its maps."""
    return author_preview_material(
        stage,
        path,
        MaterialTextures(
            *(f"./Textures/{style}_{r}.png" for r in ("basecolor", "roughness", "normal"))
        ),
        st_scale=st_scale,
        specular_tint=specular_tint,
    )


#: linear diffuse colours of the stand-in materials (no texture: the maps are in a build folder)
_STAND_IN_COLOURS = {
    "Travertine": (0.80, 0.76, 0.66),
    "Tufa": (0.55, 0.50, 0.40),
    "Stucco": (0.90, 0.88, 0.83),
    "Terracotta": (0.60, 0.28, 0.16),
}


def stand_in_materials(layers: list[Sdf.Layer]) -> Sdf.Layer:
    """A material library for layers shipped outside a build folder: every material their
    bindings target, as a plain ``UsdPreviewSurface`` of one colour under the same path (the
    temple's ``materials.usda`` holds the textured ones), so each layer that sublayers it
    opens alone and validates."""
    targets: set[Sdf.Path] = set()

    def visit(spec: Sdf.PrimSpec) -> None:
        for rel in spec.relationships:
            if rel.name.startswith("material:binding"):
                targets.update(rel.targetPathList.GetAddedOrExplicitItems())
        for child in spec.nameChildren:
            visit(child)
        for vset in spec.variantSets.values():
            for variant in vset.variants.values():
                visit(variant.primSpec)

    for layer in layers:
        for spec in layer.rootPrims:
            visit(spec)
    root = Sdf.Layer.CreateAnonymous(".usda")  # held by the caller (a stage's is not)
    stage = Usd.Stage.Open(root)
    root.comment = "stand-in materials (one colour each) for the layers shipped in layers/"
    for path in sorted(targets):
        for anc in path.GetParentPath().GetPrefixes():
            if not stage.GetPrimAtPath(anc):
                stage.DefinePrim(anc, "Xform" if anc.pathElementCount == 1 else "Scope")
        mat = UsdShade.Material.Define(stage, path)
        shader = UsdShade.Shader.Define(stage, path.AppendChild("PreviewSurface"))
        shader.CreateIdAttr("UsdPreviewSurface")
        colour = _STAND_IN_COLOURS.get(path.name, (0.7, 0.7, 0.7))
        shader.CreateInput("diffuseColor", Sdf.ValueTypeNames.Color3f).Set(Gf.Vec3f(*colour))
        shader.CreateInput("roughness", Sdf.ValueTypeNames.Float).Set(0.8)
        mat.CreateSurfaceOutput().ConnectToSource(shader.ConnectableAPI(), "surface")
    tops = [p for p in stage.GetPseudoRoot().GetChildren()]
    if tops:
        stage.SetDefaultPrim(tops[0])
        Usd.ModelAPI(tops[0]).SetKind("assembly")
    from pxr import UsdGeom

    UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.y)
    UsdGeom.SetStageMetersPerUnit(stage, 1.0)
    return root
