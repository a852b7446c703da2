"""Opening a scene for reading and selecting its variants (``--variant set=value``, ``--lod``).

:func:`open_stage` loads every payload and names the file in its errors; :func:`select_variants`
makes selections in the session layer, de-instancing what it must so instance proxies can
carry them. :mod:`ionic_usd.usd.reader` and :mod:`ionic_usd.usd.package` (usdz) start here.
(Authoring-side selection of the temple's reconstruction combinations is
:func:`ionic_usd.usd.combinations.select_variants`.)
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from pathlib import Path

from pxr import Sdf, Usd

from ionic_usd.errors import ParameterError, UsdAuthoringError

__all__ = ["open_stage", "parse_variant_args", "select_variants"]


def open_stage(path: str | os.PathLike) -> Usd.Stage:
    """Open a USD file with every payload loaded; errors name the file."""
    p = Path(path)
    if not p.is_file():
        raise ParameterError("scene", str(p), "an existing USD file (.usd, .usda, .usdc, .usdz)")
    try:
        stage = Usd.Stage.Open(str(p), Usd.Stage.LoadAll)
    except Exception as exc:  # pxr raises Tf.ErrorException carrying the parser's message
        msg = " ".join(str(exc).split())[:300]
        raise UsdAuthoringError(f"{p}: cannot open as a USD stage: {msg}") from None
    if stage is None:
        raise UsdAuthoringError(f"{p}: cannot open as a USD stage")
    return stage


def parse_variant_args(items: Sequence[str] | None) -> dict[str, str]:
    """``["lod=low", "finish=stucco"]`` → ``{"lod": "low", "finish": "stucco"}``."""
    out: dict[str, str] = {}
    for item in items or ():
        name, sep, value = item.partition("=")
        if not sep or not name.strip() or not value.strip():
            raise ParameterError("--variant", item, "SET=VALUE, e.g. lod=low")
        out[name.strip()] = value.strip()
    return out


def _outermost_instance(prim: Usd.Prim) -> Usd.Prim:
    """The instance prim (not a proxy) that makes ``prim`` an instance proxy."""
    p = prim
    while p and (p.IsInstanceProxy() or not p.IsInstance()):
        p = p.GetParent()
    return p


def select_variants(
    stage: Usd.Stage, selections: Mapping[str, str], *, require_sets: bool = True
) -> dict[str, str]:
    """Select ``set=value`` on every prim that has the set, in the session layer.

    Prims reached only through instancing (instance proxies) cannot carry a selection, so the
    instance above them is made non-instanceable in the session layer first (its nested
    instances stay instanced). Repeats until stable, because a selection can compose in prims
    with variant sets of their own. Raises ParameterError for a set no prim has, or a value a
    prim's set does not offer (listing the valid ones); with ``require_sets=False`` a set no
    prim has is ignored. Returns the selections made.
    """
    found: set[str] = set()
    session = stage.GetSessionLayer()
    with Usd.EditContext(stage, session):
        for _ in range(64):
            deinstance: dict[str, Usd.Prim] = {}
            select: list[tuple[Usd.Prim, str, str]] = []
            for prim in Usd.PrimRange(stage.GetPseudoRoot(), Usd.TraverseInstanceProxies()):
                if not prim.HasVariantSets():
                    continue
                vsets = prim.GetVariantSets()
                names = vsets.GetNames()
                for vset_name, value in selections.items():
                    if vset_name not in names:
                        continue
                    found.add(vset_name)
                    vset = vsets.GetVariantSet(vset_name)
                    valid = vset.GetVariantNames()
                    if value not in valid:
                        raise ParameterError(
                            f"--variant {vset_name}",
                            value,
                            f"one of {', '.join(valid)}",
                            context=str(prim.GetPath()),
                        )
                    if vset.GetVariantSelection() == value:
                        continue
                    if prim.IsInstanceProxy():
                        inst = _outermost_instance(prim)
                        deinstance[str(inst.GetPath())] = inst
                    else:
                        select.append((prim, vset_name, value))
            if not deinstance and not select:
                break
            with Sdf.ChangeBlock():
                for inst in deinstance.values():
                    inst.SetInstanceable(False)
                for prim, vset_name, value in select:
                    prim.GetVariantSets().GetVariantSet(vset_name).SetVariantSelection(value)
        else:  # pragma: no cover - would need a pathological stage
            raise UsdAuthoringError("variant selections did not settle after 64 passes")
    missing = [s for s in selections if s not in found]
    if missing and require_sets:
        sets: set[str] = set()
        for prim in Usd.PrimRange(stage.GetPseudoRoot(), Usd.TraverseInstanceProxies()):
            if prim.HasVariantSets():
                sets.update(prim.GetVariantSets().GetNames())
        valid = ", ".join(sorted(sets)) or "none: the scene has no variant sets"
        raise ParameterError(
            "--variant",
            missing[0],
            f"a variant set of the scene ({valid}); the scene has no {missing[0]!r} variant set",
        )
    return {k: v for k, v in selections.items() if k in found}
