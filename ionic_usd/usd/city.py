"""City scale: many temples as instanceable references, street colonnades as a PointInstancer.

``compose_city`` writes ``City.usda`` beside (or around) a temple folder written by
:func:`ionic_usd.usd.temple.compose_temple`::

    <folder>/City.usda           /City (kind = assembly)
      /City/Temples/Temple_<i>_<j>   instanceable references to ./<temple>/Temple.usda, on a
                                     grid; each may select its own reconstruction hypotheses
      /City/Porticus             a UsdGeom.PointInstancer of the column asset (lod = low) lining
                                 the streets between the blocks: thousands of columns, one
                                 prototype, arrays instead of prims
    <folder>/<temple>/           the temple (and its column asset)

Temples that make the same variant selections share one prototype, so a city of N temples
with k different hypothesis combinations composes k temple prototypes (plus the column
prototypes inside them).
"""

from __future__ import annotations

import os
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from pxr import Gf, Sdf, Usd, Vt

from ionic_usd.errors import OutputExistsError, ParameterError, UsdAuthoringError
from ionic_usd.usd.column_asset import ASSET_NAME
from ionic_usd.usd.stage import new_layer, save_layer

__all__ = ["CityReport", "compose_city"]


@dataclass(frozen=True)
class CityReport:
    path: Path
    temples: int
    temple_prototypes: int
    street_columns: int
    seconds: float


def compose_city(
    folder: str | os.PathLike,
    temple: str = "PortunusTemple",
    *,
    rows: int = 4,
    cols: int = 4,
    block: float = 60.0,
    column_spacing: float = 3.0,
    variety: bool = True,
    seed: int = 0,
    force: bool = False,
) -> CityReport:
    """Write ``<folder>/City.usda`` around an existing temple folder ``<folder>/<temple>``.

    Parameters
    ----------
    rows, cols : temples on the grid (each ≥ 1)
    block : grid spacing (m); streets run halfway between the blocks
    column_spacing : axial spacing of the street colonnades (m)
    variety : give each temple a random choice among its realised hypotheses (seeded), so the
        city shows alternative readings side by side; off: every temple at the baseline
    """
    t0 = time.perf_counter()
    folder = Path(folder)
    root_temple = folder / temple / "Temple.usda"
    if not root_temple.is_file():
        raise UsdAuthoringError(f"no temple at {root_temple}: write one first "
                                f"(ionic-usd temple -o {folder / temple})")
    for name, v in (("rows", rows), ("cols", cols)):
        if not isinstance(v, int) or v < 1:
            raise ParameterError(name, v, "an integer >= 1")
    if not (block > 0 and column_spacing > 0):
        raise ParameterError("block/column_spacing", (block, column_spacing), "lengths > 0")
    out = folder / "City.usda"
    if out.exists() and not force:
        raise OutputExistsError(f"{out} exists; pass --force (force=True) to overwrite it")

    temple_stage = Usd.Stage.Open(str(root_temple))
    vsets = temple_stage.GetDefaultPrim().GetVariantSets()
    hyps = [n for n in vsets.GetNames() if n.startswith("hyp_")]
    rng = np.random.default_rng(seed)

    layer = new_layer("City", kind="assembly")
    with Sdf.ChangeBlock():
        grp = Sdf.CreatePrimInLayer(layer, "/City/Temples")
        grp.specifier, grp.typeName, grp.kind = Sdf.SpecifierDef, "Xform", "group"
        for i in range(rows):
            for j in range(cols):
                spec = Sdf.CreatePrimInLayer(layer, f"/City/Temples/Temple_{i}_{j}")
                spec.specifier, spec.typeName = Sdf.SpecifierDef, "Xform"
                spec.instanceable = True
                spec.referenceList.Prepend(Sdf.Reference(f"./{temple}/Temple.usda"))
                for h in hyps:
                    alt = variety and rng.random() < 0.3
                    spec.variantSelections[h] = "alternative" if alt else "baseline"
                T = Sdf.ValueTypeNames
                Sdf.AttributeSpec(spec, "xformOp:translate", T.Double3).default = Gf.Vec3d(
                    j * block, 0.0, -i * block)
                Sdf.AttributeSpec(spec, "xformOpOrder", T.TokenArray,
                                  Sdf.VariabilityUniform).default = Vt.TokenArray(
                    ["xformOp:translate"])
    # Sdf API throughout: a Usd.Stage on the unsaved layer would try to resolve the relative
    # references before the file exists
    pos = _street_columns(rows, cols, block, column_spacing)
    T = Sdf.ValueTypeNames
    with Sdf.ChangeBlock():
        pi = Sdf.CreatePrimInLayer(layer, "/City/Porticus")
        pi.specifier, pi.typeName = Sdf.SpecifierDef, "PointInstancer"
        protos = Sdf.CreatePrimInLayer(layer, "/City/Porticus/Prototypes")
        protos.specifier, protos.typeName = Sdf.SpecifierDef, "Scope"
        col = Sdf.CreatePrimInLayer(layer, "/City/Porticus/Prototypes/Column")
        col.specifier, col.typeName = Sdf.SpecifierDef, "Xform"
        col.referenceList.Prepend(Sdf.Reference(f"./{temple}/{ASSET_NAME}/{ASSET_NAME}.usda"))
        col.variantSelections["lod"] = "low"
        rel = Sdf.RelationshipSpec(pi, "prototypes", custom=False)
        rel.targetPathList.explicitItems = [col.path]
        Sdf.AttributeSpec(pi, "positions", T.Point3fArray).default = Vt.Vec3fArray.FromNumpy(
            pos.astype(np.float32))
        Sdf.AttributeSpec(pi, "protoIndices", T.IntArray).default = Vt.IntArray.FromNumpy(
            np.zeros(len(pos), dtype=np.int32))
        Sdf.AttributeSpec(pi, "orientations", T.QuathArray).default = Vt.QuathArray(
            [Gf.Quath(1, 0, 0, 0)] * len(pos))
        lo, hi = pos.min(axis=0) - 1.0, pos.max(axis=0) + np.array([1.0, 9.0, 1.0])
        Sdf.AttributeSpec(pi, "extent", T.Float3Array).default = Vt.Vec3fArray(
            [Gf.Vec3f(*lo), Gf.Vec3f(*hi)])
    save_layer(layer, out, force=force)
    check = Usd.Stage.Open(str(out))
    protos = {p.GetPrototype() for p in check.GetPrimAtPath("/City/Temples").GetChildren()}
    return CityReport(out, rows * cols, len(protos), len(pos), time.perf_counter() - t0)


def _street_columns(rows: int, cols: int, block: float, spacing: float) -> np.ndarray:
    """(n, 3) column positions on both sides of the streets running along x between rows."""
    x0, x1 = -block / 2, (cols - 0.5) * block
    xs = np.arange(x0, x1 + 1e-9, spacing)
    zs = []
    for i in range(rows - 1):
        mid = -(i + 0.5) * block
        zs += [mid - 4.0, mid + 4.0]  # an 8 m street with a colonnade on each side
    if not zs:
        zs = [block / 2 - 4.0]
    xx, zz = np.meshgrid(xs, np.array(zs))
    return np.stack([xx.ravel(), np.zeros(xx.size), zz.ravel()], axis=1)
