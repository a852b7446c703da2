"""True ``extentsHint`` values under variants (``UsdGeom.ModelAPI.ComputeExtentsHint``).

A model's bounds depend on some of its variant sets (the column's ``lod``, ``base``, ``form``;
the temple's ``lod`` and the hypotheses that reshape it) and not on others (``finish``). The
hints are computed on the composed stage for every combination of the candidate sets, and then
authored without nested variant sets (a product of nested sets, one hint per combination,
made NVIDIA's validator enumerate for hours): for each prim, a hint that depends on no set is
authored on the prim; otherwise the one set that explains the hint best is picked and, inside
each of its variants, the union of the hints of the combinations with that variant is authored.
The hint is then exact where it depends on one set only and otherwise a *conservative* bound:
it contains the bound of the current combination, and each of its faces is reached by some
combination of that variant (see docs/usd.md).
"""

from __future__ import annotations

import itertools
from collections.abc import Mapping, Sequence

import numpy as np
from pxr import Gf, Sdf, Usd, UsdGeom, Vt

__all__ = [
    "bbox_cache",
    "bound_changing_sets",
    "variant_extents_hints",
    "toggled_extents_hints",
    "author_extents_hints",
    "relevant_sets",
    "split_hints",
    "union_hint",
]

Combo = tuple[str, ...]


def variant_extents_hints(
    stage: Usd.Stage,
    root: str,
    prims: Sequence[str],
    vsets: Mapping[str, Sequence[str]],
    *,
    memo: dict[tuple[tuple[str, str], ...], dict[str, np.ndarray]] | None = None,
) -> dict[Combo, dict[str, np.ndarray]]:
    """Hints of ``prims`` for every combination of ``vsets`` selected on ``root``.

    Selections are made in the stage's session layer, which is cleared afterwards. ``memo``
    (shared by calls on the same stage, root and prims) keeps the hints of each composition
    — keyed by the selections that differ from the authored ones — so that a combination
    already composed by an earlier call is not composed again.

    Returns
    -------
    combination (one variant per set, in ``vsets`` order) → prim path → (2·p, 3) float
    hint (p purposes, as ``ComputeExtentsHint`` returns them)
    """
    session = stage.GetSessionLayer()
    names = list(vsets)
    out: dict[Combo, dict[str, np.ndarray]] = {}
    prim = stage.GetPrimAtPath(root)
    authored = {n: prim.GetVariantSet(n).GetVariantSelection() for n in names}
    with Usd.EditContext(stage, session):
        try:
            for combo in itertools.product(*(vsets[n] for n in names)):
                key = tuple(
                    sorted((n, v) for n, v in zip(names, combo, strict=True) if v != authored[n])
                )
                if memo is not None and key in memo:
                    out[combo] = memo[key]
                    continue
                with Sdf.ChangeBlock():
                    for n, v in zip(names, combo, strict=True):
                        prim.GetVariantSet(n).SetVariantSelection(v)
                cache = bbox_cache(stage, UsdGeom.Imageable.GetOrderedPurposeTokens())
                out[combo] = {
                    p: np.array(
                        UsdGeom.ModelAPI(stage.GetPrimAtPath(p)).ComputeExtentsHint(cache),
                        dtype=np.float64,
                    ).reshape(-1, 3)
                    for p in prims
                }
                if memo is not None:
                    memo[key] = out[combo]
        finally:
            session.Clear()
    return out


def bbox_cache(stage: Usd.Stage, purposes) -> UsdGeom.BBoxCache:
    """A ``BBoxCache`` for ``stage``: on a stage opened without its payloads
    (``Usd.Stage.LoadNone``) the unloaded models are bounded by their ``extentsHint`` (an
    asset's own hints, per variant combination: the temple's checks need no column geometry),
    on a loaded one every bound comes from the geometry."""
    unloaded = not stage.GetLoadRules().IsLoaded(Sdf.Path.absoluteRootPath)  # O(1), no traversal
    return UsdGeom.BBoxCache(Usd.TimeCode.Default(), purposes, useExtentsHint=unloaded)


def _identity_below(stage: Usd.Stage, root: str) -> bool:
    """Whether every prim below ``root`` (down to the instancers, whose bound is their extent)
    has an identity local transform: then ``BBoxCache`` combines the children's bounds as a
    plain union of ranges, which :func:`toggled_extents_hints` reproduces."""
    ident = Gf.Matrix4d(1.0)
    it = iter(Usd.PrimRange(stage.GetPrimAtPath(root)))
    next(it)  # the root's own transform is outside its untransformed bound
    for p in it:
        if p.IsInstance() or p.IsA(UsdGeom.PointInstancer):
            it.PruneChildren()
        if p.IsInstance():
            return False
        x = UsdGeom.Xformable(p)
        if x and (x.GetResetXformStack() or x.GetLocalTransformation() != ident):
            return False
    return True


def _hint(ranges: Sequence[Gf.Range3d]) -> np.ndarray:
    """``UsdGeom.ModelAPI.ComputeExtentsHint``'s array from one range per ordered purpose:
    (2·p, 3), trailing empty purposes dropped (one empty range if all are)."""
    last = max((i for i, r in enumerate(ranges) if not r.IsEmpty()), default=0)
    flat = Vt.Vec3fArray(
        [Gf.Vec3f(v) for r in ranges[: last + 1] for v in (r.GetMin(), r.GetMax())]
    )
    return np.array(flat, dtype=np.float64).reshape(-1, 3)


def toggled_extents_hints(
    stage: Usd.Stage,
    root: str,
    items: Mapping[str, Mapping[str, str]],
    vsets: Mapping[str, Sequence[str]],
) -> dict[Combo, dict[str, np.ndarray]] | None:
    """The hints of :func:`variant_extents_hints` on ``root`` alone, for a model whose variants
    only switch ``items`` on and off: prim path → tags (set → the variant it is active in; it
    is active where every tag matches). Each item's bound is computed once and the bound of a
    combination is the union of its active items' bounds and the rest's (two compositions
    instead of one per combination). None where that union is not what ``BBoxCache`` computes
    (a transform below ``root``, nested items, a tag on a set not in ``vsets``): use
    :func:`variant_extents_hints` then.
    """
    paths = list(items)
    if any(s not in vsets for tags in items.values() for s in tags):
        return None  # a tag on a set not enumerated: its selection is not known here
    known = {Sdf.Path(p) for p in paths}
    if any(a in known for p in known for a in p.GetAncestorsRange() if a != p):
        return None  # an item inside another
    session = stage.GetSessionLayer()
    try:
        _set_active(session, paths, True)
        if not _identity_below(stage, root):
            return None
        item_bounds = _purpose_bounds(stage, paths)
        _set_active(session, paths, False)
        (rest,) = _purpose_bounds(stage, [root])
    finally:
        session.Clear()
    combos, active = _active_items(items, paths, vsets)
    item_lo, item_hi = _corners(item_bounds)
    rest_lo, rest_hi = _corners([rest])
    out: dict[Combo, dict[str, np.ndarray]] = {}
    for c, combo in enumerate(combos):
        on = active[c]
        lo = np.minimum(rest_lo[0], item_lo[on].min(axis=0)) if on.any() else rest_lo[0]
        hi = np.maximum(rest_hi[0], item_hi[on].max(axis=0)) if on.any() else rest_hi[0]
        ranges = [
            Gf.Range3d() if np.any(a > b) else Gf.Range3d(Gf.Vec3d(*a), Gf.Vec3d(*b))
            for a, b in zip(lo.tolist(), hi.tolist(), strict=True)
        ]
        out[combo] = {root: _hint(ranges)}
    return out


def _purpose_bounds(stage: Usd.Stage, prim_paths: Sequence[str]) -> list[list[Gf.Range3d]]:
    """Each prim's untransformed bound per purpose (empty where the prim is missing); one
    cache per purpose, shared by the prims of one composition."""
    purposes = UsdGeom.Imageable.GetOrderedPurposeTokens()
    caches = [bbox_cache(stage, [p]) for p in purposes]
    out = []
    for path in prim_paths:
        prim = stage.GetPrimAtPath(path)
        out.append(
            [
                c.ComputeUntransformedBound(prim).ComputeAlignedRange() if prim else Gf.Range3d()
                for c in caches
            ]
        )
    return out


def _set_active(session: Sdf.Layer, paths: Sequence[str], active: bool) -> None:
    """Every item of ``paths`` made active or inactive in the session layer."""
    with Sdf.ChangeBlock():
        for path in paths:
            spec = Sdf.CreatePrimInLayer(session, path)
            spec.specifier = Sdf.SpecifierOver
            spec.active = active


def _active_items(
    items: Mapping[str, Mapping[str, str]], paths: Sequence[str], vsets: Mapping[str, Sequence[str]]
) -> tuple[list[tuple], np.ndarray]:
    """Every combination of ``vsets`` and ``active[c, i]``: item i is on in combination c
    (every tag matches)."""
    names = list(vsets)
    combos = list(itertools.product(*(vsets[n] for n in names)))
    active = np.ones((len(combos), len(paths)), dtype=bool)
    for k, n in enumerate(names):
        chosen = np.array([c[k] for c in combos], dtype=object)
        for i, path in enumerate(paths):
            want = items[path].get(n)
            if want is not None:
                active[:, i] &= chosen == want
    return combos, active


def _corners(bs: list[list[Gf.Range3d]]) -> tuple[np.ndarray, np.ndarray]:
    """Min and max corners per purpose (items × purposes × 3); an empty range is
    (+inf, -inf), so a union takes min/max of the very doubles Gf.Range3d.UnionWith
    compares."""
    n_purposes = len(UsdGeom.Imageable.GetOrderedPurposeTokens())
    lo = np.array([[r.GetMin() if not r.IsEmpty() else (np.inf,) * 3 for r in b] for b in bs])
    hi = np.array([[r.GetMax() if not r.IsEmpty() else (-np.inf,) * 3 for r in b] for b in bs])
    return lo.reshape(len(bs), n_purposes, 3), hi.reshape(len(bs), n_purposes, 3)


def _same(a: dict[str, np.ndarray], b: dict[str, np.ndarray], tol: float) -> bool:
    return all(a[k].shape == b[k].shape and np.allclose(a[k], b[k], atol=tol, rtol=0) for k in a)


def _codes(combos: Sequence[Combo]) -> np.ndarray:
    """(c, s) int64: each combination's variants numbered per set (in order of appearance)."""
    numbering: list[dict[str, int]] = [{} for _ in combos[0]] if combos else []
    return np.array(
        [[d.setdefault(v, len(d)) for d, v in zip(numbering, c, strict=True)] for c in combos],
        dtype=np.int64,
    ).reshape(len(combos), len(numbering))


def _flat(values: Sequence[Sequence[np.ndarray]]) -> tuple[np.ndarray, np.ndarray]:
    """Each combination's arrays as one zero-padded float64 row (c, l), and (c,) the id of
    its shapes: two combinations are :func:`_same` where their ids are equal and their rows
    close (the padding then sits in the same places)."""
    shapes: dict[tuple, int] = {}
    sig = np.array([shapes.setdefault(tuple(a.shape for a in v), len(shapes)) for v in values])
    rows = [np.concatenate([np.ravel(a) for a in v]) if v else np.zeros(0) for v in values]
    flat = np.zeros((len(rows), max((len(r) for r in rows), default=0)))
    for i, r in enumerate(rows):
        flat[i, : len(r)] = r
    return flat, sig


def _relevant(codes: np.ndarray, flat: np.ndarray, sig: np.ndarray, tol: float) -> list[int]:
    """:func:`relevant_sets` on :func:`_codes` and :func:`_flat`: a set is dropped if, grouped
    by the remaining sets, every combination is :func:`_same` as the first of its group."""
    keep = list(range(codes.shape[1]))
    radix = codes.max(axis=0, initial=0) + 1 if len(codes) else np.ones(codes.shape[1], int)
    for i in range(codes.shape[1]):
        trial = [k for k in keep if k != i]
        key = np.zeros(len(codes), dtype=np.int64)
        for k in trial:  # mixed radix: one integer per combination of the remaining sets
            key = key * radix[k] + codes[:, k]
        _, first, inv = np.unique(key, return_index=True, return_inverse=True)
        ref = first[inv.reshape(-1)]
        close = np.isclose(flat, flat[ref], rtol=0, atol=tol).all(axis=1)
        if bool(np.all((sig == sig[ref]) & close)):
            keep = trial
    return keep


def relevant_sets(
    hints: Mapping[Combo, dict[str, np.ndarray]], names: Sequence[str], *, tol: float = 1e-6
) -> list[str]:
    """The sets whose selection changes some hint (the others are dropped one by one, each
    only if the hints stay a function of the remaining sets)."""
    combos = list(hints)
    flat, sig = _flat([list(h.values()) for h in hints.values()])
    codes = _codes(combos) if combos else np.zeros((0, len(names)), dtype=np.int64)
    return [names[k] for k in _relevant(codes, flat, sig, tol)]


def _variant_prim(spec: Sdf.PrimSpec, vset: str, variant: str) -> Sdf.PrimSpec:
    vs = spec.variantSets.get(vset)
    if vs is None:
        vs = Sdf.VariantSetSpec(spec, vset)
        spec.variantSetNameList.Prepend(vset)
    var = vs.variants.get(variant)
    if var is None:
        var = Sdf.VariantSpec(vs, variant)
    return var.primSpec


def _author_hint(spec: Sdf.PrimSpec, rel: Sdf.Path, hint: np.ndarray) -> None:
    target = spec
    for name in [] if rel == Sdf.Path(".") else rel.pathString.split("/"):
        child = target.nameChildren.get(name)
        if child is None:
            child = Sdf.PrimSpec(target, name, Sdf.SpecifierOver)
        target = child
    attr = target.attributes.get("extentsHint")
    if attr is None:
        attr = Sdf.AttributeSpec(
            target, "extentsHint", Sdf.ValueTypeNames.Float3Array, Sdf.VariabilityUniform
        )
    attr.default = Vt.Vec3fArray.FromNumpy(np.ascontiguousarray(hint, dtype=np.float32))


def _corner_stack(hints: Sequence[np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """(k, n, 3) min and max corners of the n purposes of each of k hints, an empty (or
    absent) purpose as (+inf, -inf)."""
    n = len(UsdGeom.Imageable.GetOrderedPurposeTokens())
    h = np.empty((len(hints), n, 2, 3))
    h[:, :, 0], h[:, :, 1] = 1.0, 0.0  # absent purposes: inverted boxes, i.e. empty
    for i, x in enumerate(hints):
        x = np.asarray(x, dtype=np.float64).reshape(-1, 2, 3)
        h[i, : len(x)] = x
    ok = np.all(h[:, :, 0] <= h[:, :, 1], axis=2, keepdims=True)  # an empty one is inverted
    return np.where(ok, h[:, :, 0], np.inf), np.where(ok, h[:, :, 1], -np.inf)


def _hint_of(lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """The hint of (n, 3) min and max corners, one pair per purpose."""
    ranges = [
        Gf.Range3d() if np.any(a > b) else Gf.Range3d(Gf.Vec3d(*a), Gf.Vec3d(*b))
        for a, b in zip(lo.tolist(), hi.tolist(), strict=True)
    ]
    return _hint(ranges)


def union_hint(hints: Sequence[np.ndarray]) -> np.ndarray:
    """The hint bounding every hint of ``hints``: per purpose, the union of their ranges."""
    lo, hi = _corner_stack(hints)
    return _hint_of(lo.min(axis=0), hi.max(axis=0))


def split_hints(
    per_combo: Mapping[Combo, np.ndarray], names: Sequence[str], *, tol: float = 1e-6
) -> tuple[str | None, dict[str, np.ndarray]]:
    """One prim's hints per combination as at most one hint per variant of ONE set: the set
    (of those that change the hint) whose variants, each bounding the union of its
    combinations, overshoot the least (summed over the combinations). Returns that set (None:
    the hint depends on no set) and variant → hint (``""`` → the one hint if None).

    The overshoot of a combination is how far its variant's union reaches past its own hint
    (the largest gap of a face, metres); the combinations are handled as arrays at once."""
    combos, hints = list(per_combo), list(per_combo.values())
    codes = _codes(combos)
    flat, sig = _flat([[h] for h in hints])
    rel = _relevant(codes, flat, sig, tol)
    lo, hi = _corner_stack(hints)
    if not rel:
        return None, {"": _hint_of(lo.min(axis=0), hi.max(axis=0))}
    best: tuple[float, str, dict[str, np.ndarray]] | None = None
    for k in rel:
        group = codes[:, k]  # the variants numbered in order of appearance, as dicts keep them
        ulo = np.array([lo[group == g].min(axis=0) for g in range(group.max() + 1)])
        uhi = np.array([hi[group == g].max(axis=0) for g in range(group.max() + 1)])
        ulo, uhi = ulo[group], uhi[group]
        finite = np.isfinite(lo) & np.isfinite(ulo)
        with np.errstate(invalid="ignore"):
            gaps = np.maximum(
                np.where(finite, lo - ulo, -np.inf), np.where(finite, uhi - hi, -np.inf)
            )
        excess = np.maximum(gaps.reshape(len(combos), -1).max(axis=1), 0.0)
        cost = sum(excess.tolist())  # summed in combination order, as floats add
        if best is None or cost < best[0]:
            firsts = np.unique(group, return_index=True)[1]
            unions = {combos[i][k]: _hint_of(ulo[i], uhi[i]) for i in sorted(firsts.tolist())}
            best = (cost, names[k], unions)
    assert best is not None
    return best[1], best[2]


def author_extents_hints(
    layer: Sdf.Layer,
    root: str,
    hints: Mapping[Combo, dict[str, np.ndarray]],
    names: Sequence[str],
    *,
    tol: float = 1e-6,
) -> dict[str, str | None]:
    """Author ``hints`` (from :func:`variant_extents_hints`) into ``layer`` on ``root`` and its
    descendants, without nesting: for each prim, a hint that depends on no set is authored
    on the prim; otherwise one hint per variant of the one set :func:`split_hints` picks,
    authored inside that variant — the union over the combinations of the other sets, a
    conservative bound. Returns prim path → that set (None: the hint is authored plainly)."""
    root_path = Sdf.Path(root)
    root_spec = layer.GetPrimAtPath(root_path)
    prims = list(next(iter(hints.values()))) if hints else []
    out: dict[str, str | None] = {}
    with Sdf.ChangeBlock():
        for path in prims:
            rel = Sdf.Path(path).MakeRelativePath(root_path)
            name, per = split_hints({c: h[path] for c, h in hints.items()}, names, tol=tol)
            out[path] = name
            for variant, hint in per.items():
                spec = root_spec if name is None else _variant_prim(root_spec, name, variant)
                _author_hint(spec, rel, hint)
    return out


def bound_changing_sets(
    stage: Usd.Stage,
    root: str,
    prims: Sequence[str],
    vsets: Mapping[str, Sequence[str]],
    *,
    base: str | None = None,
    tol: float = 1e-6,
    memo: dict[tuple[tuple[str, str], ...], dict[str, np.ndarray]] | None = None,
) -> dict[str, Sequence[str]]:
    """The sets of ``vsets`` whose selection changes some hint when switched alone — under
    each variant of ``base`` (e.g. ``lod``: a level of detail can hide a change), the other sets
    at their authored selections: the sets worth enumerating together.

    A set that moves no bound on its own is dropped before the product of the rest is taken
    (a few short passes instead of one pass over every combination); the temple's tests
    compose combinations of every set and compare the authored hints with
    ``UsdGeom.BBoxCache`` to show that nothing that matters was dropped. ``memo``: as in
    :func:`variant_extents_hints` (the passes share their ``base`` × authored combinations,
    and a later product of the kept sets shares those of one set switched alone).
    """
    keep: dict[str, Sequence[str]] = {}
    if base is not None:
        keep[base] = vsets[base]
    for name, variants in vsets.items():
        if name == base:
            continue
        sets = {base: vsets[base], name: variants} if base is not None else {name: variants}
        hints = variant_extents_hints(stage, root, prims, sets, memo=memo)
        groups: dict[str, list[dict[str, np.ndarray]]] = {}
        for combo, h in hints.items():
            groups.setdefault(combo[0] if base is not None else "", []).append(h)
        if any(not _same(g[0], h, tol) for g in groups.values() for h in g[1:]):
            keep[name] = variants
    return keep
