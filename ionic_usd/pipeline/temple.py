"""The temple's coordinator: the column asset, then the temple's layers, into one folder.

:func:`compose_temple` writes the folder :mod:`ionic_usd.usd.temple` describes, in three steps:

1. **plan** (:func:`ionic_usd.blueprint.temple_plan.plan_temple`): the asset options, the hypothesis
   layers, the detail and the cuboids, validated before anything is written;
2. **asset** (:func:`ionic_usd.pipeline.asset.build_column_asset`) into ``IonicColumn/``, and
   the roof's terracotta maps;
3. **layers** (:func:`ionic_usd.usd.temple.write_temple`): parts, colonnade, detail,
   hypotheses, the combination checks and the extentsHints;

all in a staging folder moved into place kill-safely (:func:`ionic_usd.io.replace_folder`).

A build is a pure function of its inputs, the code and the libraries, so it is keyed
(:func:`ionic_usd.pipeline.keys.build_key`) and the key is kept in the folder's manifest with the
SHA-256 of every generated file. A rebuild of the same key into a folder whose generated files
are all intact writes nothing (``rebuild=True`` regenerates anyway); one whose asset options are
unchanged copies the asset's verified files instead of building it again. Either way the bytes
in the folder are those a fresh build writes; the user's files (``overrides.usda`` and anything
else the build did not generate) are never read into the key, nor touched.
"""

from __future__ import annotations

import hashlib
import logging
import os
import shutil
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ionic_usd.blueprint.layers import ASSET_NAME, OVERRIDES_LAYER, ROOT_LAYER
from ionic_usd.checks import check_stone_options
from ionic_usd.errors import OutputExistsError
from ionic_usd.io import manifest_record, replace_folder, up_to_date
from ionic_usd.pipeline.keys import build_key, file_digests

if TYPE_CHECKING:
    from ionic_usd.blueprint.column_asset import ColumnAssetOptions
    from ionic_usd.column.column import ColumnParams
    from ionic_usd.temple.layout import TempleLayout
    from ionic_usd.temple.mouldings import MouldingParams

__all__ = ["TempleReport", "compose_temple", "current_temple", "temple_key"]

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class TempleReport:
    """What :func:`compose_temple` wrote (or found current): the root layer, files in the folder,
    and of the scene as it composes (defaults selected, the user's ``overrides.usda`` applied):
    prims, native column instances, prototypes, drawn triangles; the hypotheses, wall seconds,
    triangles per LOD and the combination layers. ``current``: the folder already held this
    build's output and nothing was written; ``asset_reused``: the column asset's files were
    copied from the previous build of the same asset options."""

    root: Path
    files: int
    prims: int
    instances: int
    prototypes: int
    triangles: int
    hypotheses: tuple[str, ...]
    seconds: float
    triangles_per_lod: dict[str, int] = field(default_factory=dict)
    combination_layers: tuple[str, ...] = ()
    current: bool = False
    asset_reused: bool = False


def temple_key(
    layout: TempleLayout,
    column: ColumnParams | None = None,
    *,
    texture_size: int = 1024,
    seed: int = 7,
    asset_options: ColumnAssetOptions | None = None,
    detail: str | None = None,
    mouldings: MouldingParams | None = None,
) -> str:
    """The content key of a temple build (see the module docstring)."""
    users = file_digests(getattr(asset_options, "user_textures", None))
    return build_key(
        "temple", layout, column, texture_size, seed, asset_options, detail, mouldings, users
    )


def _count_files(dest: Path) -> int:
    return sum(1 for f in dest.rglob("*") if f.is_file())


def _composed_counts(dest: Path, record: dict) -> dict:
    """The scene's counts as the user opens it: the generated ones, unless the user's layer
    differs from the empty one the build wrote (then the folder is composed and counted)."""
    try:
        user = hashlib.sha256((dest / OVERRIDES_LAYER).read_bytes()).hexdigest()
    except OSError:
        user = ""
    if user == record.get("overrides_sha256"):
        return record
    from ionic_usd.usd.temple import temple_counts

    return temple_counts(dest / ROOT_LAYER)


def _report(dest: Path, record: dict, t0: float, **flags: bool) -> TempleReport:
    counts = _composed_counts(dest, record)
    return TempleReport(
        root=dest / ROOT_LAYER,
        files=_count_files(dest),
        prims=int(counts["prims"]),
        instances=int(counts["instances"]),
        prototypes=int(counts["prototypes"]),
        triangles=int(counts["triangles"]),
        hypotheses=tuple(record["hypotheses"]),
        seconds=time.perf_counter() - t0,
        triangles_per_lod={str(k): int(v) for k, v in record["triangles_per_lod"].items()},
        combination_layers=tuple(record["combination_layers"]),
        current=flags.get("current", False),
        asset_reused=bool(record.get("asset_reused", False)),
    )


def _reuse_asset(dest: Path, tmp: Path, asset_key: str) -> bool:
    """Copy the previous build's column asset into ``tmp`` when it was built from the same
    options and every one of its files still has the bytes that build wrote."""
    _, record, sums = manifest_record(dest)
    if record.get("asset_key") != asset_key:
        return False
    prefix = f"{ASSET_NAME}/"
    files = {rel: h for rel, h in sums.items() if rel.startswith(prefix)}
    if not files:
        return False
    for rel, digest in files.items():
        src = dest / rel
        try:
            if src.is_symlink():
                raise OSError("a symlink")
            data = src.read_bytes()
        except OSError:
            data = b""
        if hashlib.sha256(data).hexdigest() != digest:
            shutil.rmtree(tmp / ASSET_NAME, ignore_errors=True)
            return False
        out = tmp / rel
        out.parent.mkdir(parents=True, exist_ok=True)
        out.write_bytes(data)
    return True


def _current(dest: Path, key: str, t0: float) -> TempleReport | None:
    record = up_to_date(dest, key)
    if record is None:
        return None
    try:
        return _report(dest, record, t0, current=True)
    except (KeyError, TypeError, ValueError, AttributeError):
        return None  # a record of another shape: build


def current_temple(
    folder: str | os.PathLike,
    layout: TempleLayout,
    column: ColumnParams | None = None,
    **options: Any,
) -> TempleReport | None:
    """The report of ``folder`` if it holds the intact output of this build (the arguments
    are :func:`compose_temple`'s), else None; reads no USD."""
    return _current(Path(folder), temple_key(layout, column, **options), time.perf_counter())


def _stage_temple(
    tmp: Path, plan, layout: TempleLayout, dest: Path, akey: str, *, reuse: bool
) -> dict[str, Any]:
    """Write the temple of ``plan`` (from ``layout``) into the staging folder ``tmp``: the
    column asset (its verified files taken from ``dest`` when ``reuse`` and its key ``akey``
    is unchanged), the stone maps and the layers; returns the record the manifest keeps."""
    from ionic_usd.blueprint.temple_plan import TERRACOTTA
    from ionic_usd.pipeline.asset import (
        build_column_asset,
        copy_stone_textures,
        warm_stone_textures,
    )
    from ionic_usd.usd.temple import temple_counts, write_temple

    reused = reuse and dest.is_dir() and _reuse_asset(dest, tmp, akey)
    # tiles repeat their map every metre (stone: every TILE_METRES = 2 m): half the size
    # keeps the texel density
    tiles = (TERRACOTTA[1], max(16, plan.opts.texture_size // 2), plan.opts.seed)
    if reused:
        log.info("the column asset is unchanged: its verified files are reused")
    else:
        log.info("building the column asset")
        # the tiles' maps are made in the asset's process pool, beside its geometry
        build_column_asset(
            tmp / ASSET_NAME, plan.opts, rebuild=True, side_jobs=[(warm_stone_textures, tiles)]
        )
    copy_stone_textures(tmp / "Textures", *tiles)
    stats = write_temple(plan, tmp)
    # counted on the staged folder: the scene as generated, with the empty user's layer
    return {
        **temple_counts(tmp / ROOT_LAYER),
        "overrides_sha256": hashlib.sha256((tmp / OVERRIDES_LAYER).read_bytes()).hexdigest(),
        **stats,
        "hypotheses": [h.id for h in layout.hypotheses],
        "asset_key": akey,
        "asset_reused": reused,
    }


def compose_temple(
    folder: str | os.PathLike,
    layout: TempleLayout,
    column: ColumnParams | None = None,
    *,
    force: bool = False,
    texture_size: int = 1024,
    seed: int = 7,
    asset_options: ColumnAssetOptions | None = None,
    detail: str | None = None,
    mouldings: MouldingParams | None = None,
    rebuild: bool = False,
) -> TempleReport:
    """Write the temple folder (see :mod:`ionic_usd.usd.temple`) atomically.

    Parameters
    ----------
    folder : output folder; an existing one needs ``force`` and is replaced atomically, keeping
        its ``overrides.usda`` and the user's other files byte for byte
    layout : the temple (e.g. :func:`ionic_usd.temple.portunus_layout`)
    column : column parameters (default: Portunus proportions at the layout's column height and
        lower diameter)
    detail : the default selection of the ``detail`` variant set (plain, moulded, carved;
        None: :data:`~ionic_usd.usd.detail.DEFAULT_DETAIL`)
    mouldings : the moulding sections (default: those of ``portunus.toml``)
    rebuild : regenerate even when ``folder`` already holds this build's intact output

    Hypothesis changes the generator cannot realise raise :class:`ParameterError` before
    anything is written.
    """
    t0 = time.perf_counter()
    check_stone_options(texture_size, seed)
    dest = Path(folder)
    if dest.exists() and not force:
        raise OutputExistsError(
            f"{dest} exists; pass --force to rebuild it (your {OVERRIDES_LAYER} is kept)"
        )
    options: dict[str, Any] = {
        "texture_size": texture_size,
        "seed": seed,
        "asset_options": asset_options,
        "detail": detail,
        "mouldings": mouldings,
    }
    key = temple_key(layout, column, **options)
    if not rebuild:
        current = _current(dest, key, t0)
        if current is not None:
            return current
    from ionic_usd.blueprint.temple_plan import plan_temple
    from ionic_usd.pipeline.asset import asset_key

    plan = plan_temple(layout, column, **options)
    akey = asset_key(plan.opts)

    def build(tmp: Path) -> dict[str, Any]:
        return _stage_temple(tmp, plan, layout, dest, akey, reuse=not rebuild)

    record = replace_folder(
        build,
        dest,
        force=force,
        keep_existing=(OVERRIDES_LAYER,),
        root_files=(ROOT_LAYER,),
        key=key,
        # the manifest holds what the folder is, never how this run made it: a repaired
        # folder's manifest is byte for byte a fresh build's
        record=lambda r: {k: v for k, v in r.items() if k != "asset_reused"},
    )
    return _report(dest, record, t0)
