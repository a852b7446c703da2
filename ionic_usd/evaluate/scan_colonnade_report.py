"""``ionic-usd fit column --scan`` on a scan of several columns: the outputs and the text
report of a :class:`.scan_colonnade.ColonnadeFit`.

Written in ``-o OUTDIR``: ``colonnade.usda`` (every column found, largest cluster first, as
instances of its group's column at its own pose: :func:`ionic_usd.usd.scan.write_colonnade`),
per column k (1, 2, …) ``scan_fit_<k>.png``; per distinct column description
``fitted_column_<A, B, …>.toml``; ``scan_deviation.usdc`` (every point's distance to its
column's description); R.json at ``--json``.
"""

from __future__ import annotations

import string
from collections.abc import Callable
from pathlib import Path
from typing import IO, Any

import numpy as np

from ionic_usd.evaluate.scan_colonnade import ColonnadeFit, _stats, fit_colonnade

__all__ = ["colonnade_files", "colonnade_instances", "run_colonnade"]


def colonnade_files(out: Path, fit: ColonnadeFit) -> dict[str, Path]:
    """Output name → path."""
    files = {"scan": out / "scan_deviation.usdc", "colonnade": out / "colonnade.usda"}
    for k in range(len(fit.fits)):
        files[f"png_{k + 1}"] = out / f"scan_fit_{k + 1}.png"
    for g in range(len(fit.groups)):
        files[f"toml_{_letter(g)}"] = out / f"fitted_column_{_letter(g)}.toml"
    return files


def _letter(g: int) -> str:
    return string.ascii_uppercase[g] if g < 26 else f"G{g + 1}"


def colonnade_instances(fit: ColonnadeFit) -> tuple[dict[str, dict], list]:
    """What :func:`ionic_usd.usd.scan.write_colonnade` writes: per group (A, B, …) its
    source's parts, built once; per column its group, pose (as an instance of the group:
    registered along its axis), the turn of the group's shaft to
    its flute phase and its deviation from the group's description."""
    from ionic_usd.column.column import build_column
    from ionic_usd.usd.scan import ColonnadeInstance

    prototypes = {
        _letter(g): build_column(fit.fits[members[0]].column).parts()
        for g, members in enumerate(fit.groups)
    }
    instances = []
    for k, f in enumerate(fit.fits):
        g = fit.group_of(k)
        src = fit.fits[fit.groups[g][0]].column.shaft.flute_phase
        turn = f.column.shaft.flute_phase - src
        dev = _stats(fit.instance_deviation[k])
        instances.append(ColonnadeInstance(_letter(g), fit.instance_matrix[k], turn, dev))
    return prototypes, instances


def _write(fit: ColonnadeFit, pts: np.ndarray, files: dict[str, Path], args: Any) -> None:
    from ionic_usd.column.column import COLUMN_DOCS, column_params_to_tables
    from ionic_usd.column.shaft import SHAFT_PARAMETER_DOCS
    from ionic_usd.evaluate.report import write_atomically, write_fit_json
    from ionic_usd.evaluate.scan_deviation import heat_colours
    from ionic_usd.evaluate.scan_report import plot_scan_fit
    from ionic_usd.params import to_toml
    from ionic_usd.usd.scan import write_colonnade, write_scan_points

    name = Path(args.scan).name
    prototypes, instances = colonnade_instances(fit)
    for k, f in enumerate(fit.fits):
        plot_scan_fit(f, files[f"png_{k + 1}"])
    write_colonnade(
        files["colonnade"],
        prototypes,
        instances,
        force=True,
        comment=f"ionic_usd colonnade fitted to {name}: {len(fit.fits)} columns, "
        f"{len(fit.groups)} distinct",
    )
    dev = np.zeros(len(pts))
    for idx, d in zip(fit.indices, fit.instance_deviation, strict=True):
        dev[idx] = d
    rest = np.ones(len(pts), dtype=bool)
    for idx in fit.indices:
        rest[idx] = False
    kept = ~rest  # dropped clusters carry no deviation: left out of the points' file
    vmax = max(float(np.percentile(dev[kept], 99)), 1e-4)
    width = 0.5 * float(np.linalg.norm(np.ptp(pts, axis=0))) / max(len(pts), 1) ** 0.5
    write_scan_points(
        files["scan"],
        pts[kept],
        dev[kept],
        heat_colours(dev[kept], vmax),
        width=max(width, 1e-4),
        force=True,
    )
    for g, members in enumerate(fit.groups):
        text = to_toml(
            column_params_to_tables(fit.fits[members[0]].column),
            {"column": COLUMN_DOCS, "shaft": SHAFT_PARAMETER_DOCS},
            header=f"ionic_usd column {_letter(g)} fitted to the scan {name} (instances "
            f"{', '.join(str(i + 1) for i in members)})",
        )
        write_atomically(files[f"toml_{_letter(g)}"], _writer(text.encode("utf-8")))
    if args.json is not None:
        write_fit_json(
            args.json,
            {},
            extra=fit.summary(),
            metadata={
                "scan": str(args.scan),
                "scale": args.scale,
                "units": getattr(args, "units", None) or "auto",
                "outputs": {k: str(v) for k, v in files.items()},
            },
        )


def _writer(data: bytes) -> Callable[[IO[bytes]], None]:
    def write(fh: IO[bytes]) -> None:
        fh.write(data)

    return write


def _mm(x: float) -> str:
    return f"{x * 1000:.3g} mm"


def run_colonnade(pts: np.ndarray, split, out: Path, args: Any, unit_note: str) -> int:
    """Fit, refuse clashing outputs, write, report (the columns of ``split``)."""
    from ionic_usd.errors import OutputExistsError

    fit = fit_colonnade(pts, seed=args.seed, split=split)
    files = colonnade_files(out, fit)
    clash = [str(p) for p in files.values() if p.exists()]
    if clash and not args.force:
        raise OutputExistsError(f"{clash[0]} exists; pass --force to overwrite it")
    out.mkdir(parents=True, exist_ok=True)
    _write(fit, pts, files, args)
    s = fit.summary()
    print(
        f"scan {args.scan}: {len(pts):,} points; {len(fit.fits)} columns, "
        f"{len(fit.groups)} distinct"
    )
    print(f"  {unit_note}")
    print(f"  up axis {np.round(fit.up, 5).tolist()}")
    for k, c in enumerate(s["columns"]):
        d, dg = c["deviation"], c["deviation_from_group"]
        print(
            f"  column {k + 1} ({_letter(c['group'])}): at {np.round(c['position'], 4).tolist()}"
            f", axis {np.round(c['axis']['direction'], 5).tolist()}; D {c['diameter']:.4f} m, "
            f"{c['flutes']} flutes; {c['points']:,} points, rms {_mm(d['rms'])}, p95 "
            f"{_mm(d['p95'])}; from {_letter(c['group'])}: rms {_mm(dg['rms'])}, p95 "
            f"{_mm(dg['p95'])}"
        )
    for g, members in enumerate(fit.groups):
        print(
            f"  column {_letter(g)}: instances {', '.join(str(i + 1) for i in members)} "
            f"(described by column {members[0] + 1}, the least rms)"
        )
    for note in fit.notes:
        print(f"  {note}")
    for p in files.values():
        print(f"wrote {p}")
    if args.json is not None:
        print(f"wrote {args.json}")
    return 0
