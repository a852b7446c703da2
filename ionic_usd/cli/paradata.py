"""The ``ionic-usd paradata`` and ``ionic-usd web`` subcommands (the Extended Matrix graph of a
temple scene; a static web presentation of it)."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from ionic_usd.cli.flags import add_command, add_output_flags

__all__ = ["add_paradata_parser", "add_web_parser", "cmd_paradata", "cmd_web"]


def cmd_paradata(args: argparse.Namespace) -> int:
    from ionic_usd.io import check_output_file
    from ionic_usd.temple.em_graphml import graph_of, write_graphml
    from ionic_usd.usd.paradata_scene import read_scene_paradata

    out = check_output_file(args.output, force=args.force, suffixes=(".graphml",))
    if not Path(args.scene).is_file():
        from ionic_usd.errors import ParameterError

        raise ParameterError("SCENE", str(args.scene), "an existing USD file")
    pd = read_scene_paradata(args.scene)
    asks = {hid: str(e.get("question") or hid) for hid, e in pd.listing.items()}
    g = graph_of(pd.parts, pd.hypotheses, asks)
    write_graphml(g, out)
    print(
        f"wrote {out}: {len(g.units)} units ({len(pd.parts)} parts, {len(pd.hypotheses)} "
        f"hypotheses), {len(g.documents)} documents, {len(g.edges)} edges"
    )
    return 0


def cmd_web(args: argparse.Namespace) -> int:
    from ionic_usd.web import write_site

    rep = write_site(args.scene, args.output, force=args.force)
    print(rep)
    return 0


def add_paradata_parser(sub: Any, full: bool) -> None:
    p = add_command(
        sub,
        "paradata",
        cmd_paradata,
        help="the scene's Extended Matrix graph (GraphML for yEd and the EM tools)",
        description="Write the reconstruction's Extended Matrix graph of a temple scene: "
        "one unit per part and per hypothesis (EM node styles), their certainty and "
        "sources (documents), in yEd GraphML. Edit it in yEd and build with "
        "`ionic-usd temple --paradata FILE`.",
    )
    if not full:
        return
    p.add_argument("scene", type=Path, help="a temple's Temple.usda")
    add_output_flags(p, "GraphML file", default="temple.graphml")


def add_web_parser(sub: Any, full: bool) -> None:
    p = add_command(
        sub,
        "web",
        cmd_web,
        help="a static web presentation of a temple scene (GLB, hypotheses, paradata)",
        description="Write a static site: the scene as GLB, a panel of its hypotheses with "
        "toggles, the reliability view, the paradata of a clicked part, a permalink. "
        "Loads nothing from the internet; serve it with `python -m http.server`.",
    )
    if not full:
        return
    p.add_argument("scene", type=Path, help="a temple's Temple.usda")
    add_output_flags(
        p, "output folder", default="site", force_help="replace an existing site folder"
    )
