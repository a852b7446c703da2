"""The web view's level-of-detail units (:func:`ionic_usd.usd.web_scene.lod_groups`)."""

from __future__ import annotations

from pxr import Kind, Usd


def test_lod_groups_are_a_citys_temples_or_the_temple(tiny_temple, tiny_city):
    from ionic_usd.usd.web_scene import lod_groups

    assert lod_groups(tiny_temple.root) == ["/Temple"]
    groups = lod_groups(tiny_city)
    stage = Usd.Stage.Open(str(tiny_city))
    temples = stage.GetPrimAtPath("/City/Temples").GetChildren()
    assert groups == [str(t.GetPath()) for t in temples] and len(groups) == 4
    # each an assembly, none inside another
    assert all(Usd.ModelAPI(t).GetKind() == Kind.Tokens.assembly for t in temples)
    assert not any(a != b and b.startswith(a + "/") for a in groups for b in groups)
