"""City scale: instanced temples sharing prototypes, a PointInstancer of columns."""

from __future__ import annotations

import shutil

import numpy as np
import pytest
from pxr import Usd, UsdGeom

from ionic_usd.errors import OutputExistsError, UsdAuthoringError
from ionic_usd.usd import validate_stage
from ionic_usd.usd.city import compose_city


def test_city_instances_temples_and_columns(portunus_temple, tmp_path):
    shutil.copytree(portunus_temple.root.parent, tmp_path / "PortunusTemple")
    rep = compose_city(tmp_path, rows=3, cols=4, seed=1)
    stage = Usd.Stage.Open(str(rep.path))
    temples = stage.GetPrimAtPath("/City/Temples").GetChildren()
    assert len(temples) == 12 and all(t.IsInstance() for t in temples)
    # temples with equal hypothesis selections share a prototype
    sels = {tuple(sorted(t.GetVariantSets().GetAllVariantSelections().items()))
            for t in temples}
    assert rep.temple_prototypes == len(sels) == len({t.GetPrototype() for t in temples})
    pi = UsdGeom.PointInstancer(stage.GetPrimAtPath("/City/Porticus"))
    pos = np.array(pi.GetPositionsAttr().Get())
    assert len(pos) == rep.street_columns > 100
    assert set(np.asarray(pi.GetProtoIndicesAttr().Get()).tolist()) == {0}
    proto = stage.GetPrimAtPath(pi.GetPrototypesRel().GetTargets()[0])
    assert proto.GetVariantSets().GetVariantSet("lod").GetVariantSelection() == "low"
    assert any(p.IsA(UsdGeom.Mesh) for p in Usd.PrimRange(proto))
    assert validate_stage(stage) == []
    base = compose_city(tmp_path, rows=3, cols=4, variety=False, force=True)
    assert base.temple_prototypes == 1
    with pytest.raises(OutputExistsError):
        compose_city(tmp_path)


def test_city_needs_a_temple(tmp_path):
    with pytest.raises(UsdAuthoringError, match="no temple"):
        compose_city(tmp_path)
    assert not (tmp_path / "City.usda").exists()
