"""The generating commands of ``ionic-usd``: shaft, column, asset, temple, preview.

Thin wrappers over the public API: each validates its flags (one-line errors, status 2, see
:mod:`ionic_usd.cli`), estimates the memory, builds and prints one result line. Everything heavy
is imported inside the command, so building the parser loads none of it.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from ionic_usd.cli.flags import collect_flags
from ionic_usd.errors import ParameterError

__all__ = [
    "PARTS",
    "cmd_asset",
    "cmd_column",
    "cmd_presets",
    "cmd_preview",
    "cmd_shaft",
    "cmd_temple",
]


# -- commands ----------------------------------------------------------------------------------
def _shaft_params(args: argparse.Namespace):
    from ionic_usd.column.shaft import ShaftParams
    from ionic_usd.params import dataclass_from_mapping, load_toml

    base = ShaftParams()
    if args.config:
        data = load_toml(args.config)
        section = data.get("shaft", data)
        if not isinstance(section, dict):
            raise ParameterError("shaft", section, "a TOML table", context=str(args.config))
        base = dataclass_from_mapping(ShaftParams, section, context=f"{args.config} [shaft]")
    flags = collect_flags(args, ShaftParams)
    params = dataclass_from_mapping(ShaftParams, flags, context="command line", base=base)
    given = flags.get("flute_slices_per_fillet_slice", base.flute_slices_per_fillet_slice)
    top = params.fillet_ratio_saturation()
    if given != ShaftParams.flute_slices_per_fillet_slice and given > top:
        # a value that changes nothing is refused (issue 31), not silently accepted
        raise ParameterError(
            "--flute-slices-per-fillet-slice",
            given,
            f"at most {top}: from $i = {top} on the fillet is one slice (fillet "
            f"{params.fillet_angle:g} deg, flute {params.flute_angle:g} deg in "
            f"{params.flute_slices} slices), so a larger $i changes nothing",
        )
    return params


def cmd_shaft(args: argparse.Namespace) -> int:
    from ionic_usd.column.shaft import (
        SHAFT_PARAMETER_DOCS,
        build_shaft,
        shaft_triangle_estimate,
    )
    from ionic_usd.params import to_toml

    params = _shaft_params(args)
    if args.print_config:
        sys.stdout.write(
            to_toml(
                {"shaft": params.to_dict()},
                {"shaft": SHAFT_PARAMETER_DOCS},
                header="ionic_usd shaft parameters (edit and pass with --config)",
            )
        )
        return 0
    from ionic_usd.usd import check_output_path, write_meshes

    out = check_output_path(args.output, force=args.force)
    _check_memory("the shaft", shaft_triangle_estimate(params), args)
    t0 = time.perf_counter()
    from ionic_usd.geometry.guard import guarded

    mesh = guarded(
        lambda: build_shaft(params, max_triangles=args.max_triangles), "shaft", "parameters"
    )
    t1 = time.perf_counter()
    write_meshes(out, {"Shaft": mesh}, root="Shaft", force=args.force)
    t2 = time.perf_counter()
    print(
        f"wrote {out}: {mesh.n_triangles:,} triangles, {mesh.n_points:,} points "
        f"(generate {1e3 * (t1 - t0):.1f} ms, write {1e3 * (t2 - t1):.1f} ms)"
    )
    return 0


def _column_params(args: argparse.Namespace):
    from ionic_usd.column.column import column_params_from_mapping, portunus_column_params
    from ionic_usd.params import load_toml

    params = portunus_column_params()
    if args.config:
        params = column_params_from_mapping(load_toml(args.config), context=str(args.config))
    # an empty value is given (and refused by the parameters), not "not given"
    flags = {
        k: getattr(args, k) for k in ("lod", "base", "scroll") if getattr(args, k, None) is not None
    }
    if flags:
        params = column_params_from_mapping({"column": flags}, context="command line", base=params)
    return params


PARTS = {
    "all": ("Base", "Shaft", "CapitalBody"),
    "base": ("Base",),
    "shaft": ("Shaft",),
    "capital": ("CapitalBody",),
    "base+shaft": ("Base", "Shaft"),
}


def cmd_column(args: argparse.Namespace) -> int:
    from ionic_usd.api import column
    from ionic_usd.column.column import COLUMN_DOCS, column_params_to_tables
    from ionic_usd.column.shaft import SHAFT_PARAMETER_DOCS
    from ionic_usd.params import to_toml

    params = _column_params(args)
    if args.print_config:
        from ionic_usd.column.capital import CAPITAL_PARAMETER_DOCS
        from ionic_usd.column.volute import VOLUTE_PARAMETER_DOCS

        docs = {
            "column": COLUMN_DOCS,
            "shaft": SHAFT_PARAMETER_DOCS,
            "capital": CAPITAL_PARAMETER_DOCS,
            "volute": VOLUTE_PARAMETER_DOCS,
        }
        sys.stdout.write(
            to_toml(
                column_params_to_tables(params),
                docs,
                header="ionic_usd column parameters (edit and pass with "
                "--config); lengths in metres, angles in degrees",
            )
        )
        return 0
    from ionic_usd.usd import check_output_path

    out = check_output_path(args.output, force=args.force)  # refused before any work
    from ionic_usd.resources import check_estimate, estimate_column

    check_estimate(estimate_column(params), args.max_memory)
    t0 = time.perf_counter()
    col = column(params)
    t1 = time.perf_counter()
    col.save(out, force=args.force, parts=PARTS[args.part])
    t2 = time.perf_counter()
    meshes = {k: v for k, v in col.parts().items() if k in PARTS[args.part]}
    tris = sum(m.n_triangles for m in meshes.values())
    print(
        f"wrote {out}: {', '.join(meshes)}; {tris:,} triangles, height {col.height:.3f} m "
        f"(generate {1e3 * (t1 - t0):.1f} ms, write {1e3 * (t2 - t1):.1f} ms)"
    )
    return 0


def cmd_asset(args: argparse.Namespace) -> int:
    from ionic_usd.blueprint.column_asset import ColumnAssetOptions
    from ionic_usd.io import check_output_folder
    from ionic_usd.pipeline.asset import build_column_asset
    from ionic_usd.resources import check_estimate, estimate_asset

    check_output_folder(args.output, force=args.force)
    params = _column_params(args)
    user: dict[str, str] | None = None
    if args.texture:
        user = {}
        roles = ("basecolor", "roughness", "normal")
        for item in args.texture:
            role, sep, path = item.partition("=")
            if not sep or role not in roles or not path:
                raise ParameterError(
                    "--texture", item, "ROLE=FILE with ROLE basecolor, roughness or normal"
                )
            if role in user:  # the last one silently winning would hide a typo
                raise ParameterError(
                    "--texture", item, f"each role once ({role} is also {user[role]!r})"
                )
            user[role] = path
    check_estimate(estimate_asset(params, args.texture_size), args.max_memory)
    opts = ColumnAssetOptions(
        params=params,
        texture_size=args.texture_size,
        seed=args.seed,
        make_tx=args.tx,
        user_textures=user,
    )
    from ionic_usd.outputs import folder_lock

    with folder_lock(args.output):  # one writer at a time
        rep = build_column_asset(args.output, opts, force=args.force, rebuild=args.rebuild)
    lods = ", ".join(f"{k} {v:,}" for k, v in rep.triangles_per_lod.items())
    done = "up to date" if rep.current else "wrote"
    print(
        f"{done} {rep.path}: {rep.meshes} meshes, triangles per LOD: {lods}; "
        f"{rep.uv_unwraps} UV unwraps, {rep.bytes_on_disk / 1e6:.1f} MB, {rep.seconds:.2f} s"
    )
    return 0


def _with_graphml_paradata(temple, path: Path):
    """``temple`` with the records an edited EM GraphML states over its own."""
    import dataclasses

    from ionic_usd.temple.em_graphml import read_graphml
    from ionic_usd.temple.paradata import PART_KEYS, default_paradata

    if not Path(path).is_file():
        raise ParameterError("--paradata", str(path), "an existing GraphML file")
    parts, hyps = read_graphml(path)
    lay = temple.layout
    pd = lay.paradata or default_paradata(lay.hypotheses)
    for unit in parts:
        if unit not in PART_KEYS and unit.split(".")[0] not in ("column", "finish"):
            raise ParameterError(
                "unit", unit, "a part key: " + ", ".join(PART_KEYS), context=str(path)
            )
    known = {h.id for h in lay.hypotheses}
    for hid in hyps:
        if hid not in known:
            raise ParameterError(
                "unit", "hyp:" + hid, "a hypothesis of the temple", context=str(path)
            )
    pd = dataclasses.replace(pd.with_parts(parts), hypotheses={**pd.hypotheses, **hyps})
    return dataclasses.replace(temple, layout=dataclasses.replace(lay, paradata=pd))


def cmd_temple(args: argparse.Namespace) -> int:
    from ionic_usd.api import Temple
    from ionic_usd.io import check_output_folder
    from ionic_usd.resources import check_estimate, estimate_temple

    check_output_folder(args.output, force=args.force)
    if args.config and args.preset is not None:
        raise ParameterError("--preset", args.preset, "not with --config (one description)")
    if args.config:
        temple = Temple.from_toml(args.config)
    elif args.preset is not None:
        from ionic_usd.temple.presets import preset_path

        temple = Temple.from_toml(preset_path(args.preset))
    else:
        layouts = {"portunus": Temple.portunus}
        if args.layout not in layouts:
            raise ParameterError(
                "--layout",
                args.layout,
                f"one of the built-in layouts: {', '.join(layouts)} "
                "(or describe a temple in a TOML file: --config)",
            )
        temple = layouts[args.layout]()
    if getattr(args, "paradata", None) is not None:
        temple = _with_graphml_paradata(temple, args.paradata)
    layout = temple.layout
    options = {"texture_size": args.texture_size, "seed": args.seed, "detail": args.detail}
    from ionic_usd.outputs import folder_lock

    with folder_lock(args.output):  # one writer at a time
        rep = None if args.rebuild else temple.current(args.output, **options)
        if rep is None:  # something to build: estimate its memory first
            n_cuboids = sum(len(c) for c in layout.cuboids.values())
            check_estimate(
                estimate_temple(temple.column_params, args.texture_size, n_cuboids),
                args.max_memory,
            )
            rep = temple.save(args.output, force=args.force, rebuild=args.rebuild, **options)
    done = "up to date" if rep.current else "wrote"
    print(
        f"{done} {rep.root} ({layout.name}): {rep.files} files, {rep.prims} prims, "
        f"{rep.instances} column instances of {rep.prototypes} prototypes, "
        f"{rep.triangles:,} triangles, {len(rep.hypotheses)} hypotheses, {rep.seconds:.2f} s"
    )
    print(
        f"  open {rep.root} in usdview, Blender, Houdini or Omniverse; put your own edits in "
        f"{Path(args.output) / 'overrides.usda'} (kept on rebuilds)"
    )
    return 0


def cmd_presets(args: argparse.Namespace) -> int:
    """The built-in temples, one a line: name, title, type, sources."""
    from ionic_usd.temple.presets import PRESETS, preset_summary

    for name in PRESETS:
        title, kind, sources = preset_summary(name)
        print(f"{name}\t{kind}\t{title}\t{'; '.join(sources)}")
    return 0


def cmd_preview(args: argparse.Namespace) -> int:
    from ionic_usd.preview import render_preview

    try:
        red, green, blue = (float(x) for x in args.background.split(","))
    except ValueError:
        raise ParameterError("--background", args.background, "three numbers R,G,B") from None
    background = (red, green, blue)
    from ionic_usd.resources import check_estimate, estimate_render

    check_estimate(estimate_render(args.width, args.height, args.samples), args.max_memory)
    s = render_preview(
        args.scene,
        args.output,
        width=args.width,
        height=args.height,
        camera=args.camera,
        lod=args.lod,
        background=background,
        samples=args.samples,
        ground=not args.no_ground,
        force=args.force,
        variants={"view": args.view} if getattr(args, "view", None) else None,
    )
    print(
        f"wrote {args.output}: {s.triangles:,} triangles, {s.meshes} meshes, "
        f"{s.instances} instances ({s.seconds:.2f} s)"
    )
    return 0


def _check_memory(what: str, triangles: int, args: argparse.Namespace) -> None:
    from ionic_usd.resources import (
        BASELINE_BYTES,
        BYTES_PER_TRIANGLE,
        Estimate,
        check_estimate,
    )

    check_estimate(
        Estimate(what, triangles, 0, BASELINE_BYTES + BYTES_PER_TRIANGLE * triangles),
        args.max_memory,
    )
