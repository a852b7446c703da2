"""Read the paradata a temple scene carries (``customData["paradata"]``, written by
:mod:`ionic_usd.usd.paradata`): the baseline units and, per hypothesis, its record and the
parts its ``alternative`` touches. Used by ``ionic-usd paradata`` and ``ionic-usd web``."""

from __future__ import annotations

import os
from dataclasses import dataclass, field

from pxr import Sdf, Usd, UsdGeom

from ionic_usd.errors import ParameterError
from ionic_usd.temple.description import Certainty
from ionic_usd.temple.paradata import Evidence, Record

__all__ = ["SceneParadata", "read_scene_paradata", "prim_record"]


@dataclass
class SceneParadata:
    """``parts``: unit key → record; ``prims``: prim path → unit key (baseline);
    ``hypotheses``: id → (record, unit keys touched); ``listing``: /Temple's hypotheses."""

    parts: dict[str, Record] = field(default_factory=dict)
    prims: dict[str, str] = field(default_factory=dict)
    hypotheses: dict[str, tuple[Record, tuple[str, ...]]] = field(default_factory=dict)
    listing: dict[str, dict] = field(default_factory=dict)


def prim_record(prim: Usd.Prim) -> tuple[str, Record] | None:
    """``(unit, record)`` of a prim carrying paradata, else None."""
    d = prim.GetCustomData().get("paradata")
    if not d:
        return None
    rec = Record(
        Evidence(d["evidence"]),
        Certainty(d["certainty"]),
        tuple(d.get("sources", ())),
        d.get("description", ""),
        "" if d.get("hypothesis") == "baseline" else d.get("hypothesis", ""),
    )
    return d["unit"], rec


def _walk(stage: Usd.Stage) -> list[tuple[str, str, Record]]:
    out = []
    # unloaded payloads (the columns' geometry) still carry their prim's paradata
    it = iter(
        Usd.PrimRange(
            stage.GetPseudoRoot(), Usd.PrimIsActive & Usd.PrimIsDefined & ~Usd.PrimIsAbstract
        )
    )
    for prim in it:
        # a detail or hypothesis hides (visibility) what it does not show, keeping its path
        img = UsdGeom.Imageable(prim)
        if img and img.GetVisibilityAttr().Get() == UsdGeom.Tokens.invisible:
            it.PruneChildren()
            continue
        got = prim_record(prim)
        if got is not None:
            out.append((str(prim.GetPath()), *got))
    return out


def read_scene_paradata(path: str | os.PathLike) -> SceneParadata:
    """The paradata of a temple scene (refused: a scene without any)."""
    try:
        stage = Usd.Stage.Open(str(path), Usd.Stage.LoadNone)
    except Exception:  # pxr raises Tf errors for files it cannot read
        stage = None
    if stage is None:
        raise ParameterError("SCENE", str(path), "a USD scene that opens")
    root = stage.GetDefaultPrim()
    if not root or not root.GetVariantSets().HasVariantSet("view"):
        raise ParameterError(
            "SCENE", str(path), "a temple built by ionic-usd temple (no paradata found)"
        )
    out = SceneParadata()
    out.listing = {
        str(v.get("id", k)): dict(v)
        for k, v in root.GetCustomData().get("ionic_usd", {}).get("hypotheses", {}).items()
    }
    session = stage.GetSessionLayer()
    spec = Sdf.CreatePrimInLayer(session, root.GetPath())
    sets = root.GetVariantSets()
    # every detail level: a part may exist in one only (the carved tiles, the mouldings)
    details = sets.GetVariantSet("detail").GetVariantNames() if sets.HasVariantSet("detail") else []
    for detail in details or [""]:
        if detail:
            spec.variantSelections["detail"] = detail
        for p, unit, rec in _walk(stage):
            if not rec.hypothesis:
                out.parts.setdefault(unit, rec)
                out.prims.setdefault(p, unit)
        for name in sets.GetNames():
            if name.startswith("hyp_"):
                for value in sets.GetVariantSet(name).GetVariantNames():
                    if value != "baseline":
                        _hypothesis(stage, spec, (name, value), out)
    return out


def _hypothesis(
    stage: Usd.Stage, spec: Sdf.PrimSpec, choice: tuple[str, str], out: SceneParadata
) -> None:
    """The parts the hypothesis selected by ``choice`` (variant set, value) touches: an
    independent one's ``alternative``, or one value of a question's set."""
    name, value = choice
    ids = {
        (str(e.get("variantSet", "")), str(e.get("variant", "alternative"))): hid
        for hid, e in out.listing.items()
    }
    want = ids.get(choice)
    spec.variantSelections[name] = value
    touched: dict[str, Record] = {}
    for _, unit, rec in _walk(stage):
        if rec.hypothesis and rec.hypothesis == want:
            touched.setdefault(unit, rec)
    del spec.variantSelections[name]
    hid = next((r.hypothesis for r in touched.values()), "")
    if hid:
        rec, before = out.hypotheses.get(hid, (next(iter(touched.values())), ()))
        out.hypotheses[hid] = (rec, tuple(sorted({*before, *touched})))
