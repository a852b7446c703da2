"""Table: part × model × diameter → paper's measure % and discrete Fréchet %, fit times.

References come from constructions independent of the generator (tools/make_examples.py),
scaled to each diameter. Run: ``python tools/fit_table.py [--out table.md]``.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from make_examples import attic_base, semicircle_flutes, twelve_centre_volute  # noqa: E402

from ionic_usd.evaluate.fit import fit_base, fit_volute  # noqa: E402
from ionic_usd.evaluate.fit_shaft import fit_shaft_section  # noqa: E402


def rows(diameters: tuple[float, ...]) -> list[tuple]:
    out = []
    for d in diameters:
        res = fit_volute(twelve_centre_volute(eye_radius=d / 36))
        for r in (res, *res.alternatives):
            out.append(
                (
                    "volute (12 centres)",
                    r.model,
                    d,
                    r.after.hausdorff_pct,
                    r.after.discrete_frechet_pct,
                    r.seconds,
                    ",".join(r.bounds_hit),
                    r.diameter,
                )
            )
        r = fit_shaft_section(semicircle_flutes(radius=d / 2 * 0.93))
        out.append(
            (
                "shaft section (semicircles)",
                r.model,
                d,
                r.after.hausdorff_pct,
                r.after.discrete_frechet_pct,
                r.seconds,
                ",".join(r.bounds_hit),
                r.diameter,
            )
        )
        t0 = time.perf_counter()
        r = fit_base(attic_base(d))
        out.append(
            (
                "base (Attic)",
                r.model,
                d,
                r.after.hausdorff_pct,
                r.after.discrete_frechet_pct,
                time.perf_counter() - t0,
                f"{len(r.bounds_hit)} coords",
                r.diameter,
            )
        )
        for row in out[-4:]:
            print(row, flush=True)
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--out", type=Path)
    ap.add_argument("--diameters", default="0.6,0.95,1.2")
    args = ap.parse_args()
    ds = tuple(float(x) for x in args.diameters.split(","))
    table = [
        "| part | model | D (m) | paper's measure % | discrete Fréchet % | fit s | "
        "bounds hit | D estimate (m) |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for p, m, d, h, f, s, hit, de in rows(ds):
        table.append(
            f"| {p} | {m} | {d:g} | {h:.3f} | {f:.3f} | {s:.1f} | {hit or '-'} | {de:.3f} |"
        )
    text = "\n".join(table)
    print(text)
    if args.out:
        args.out.write_text(text + "\n", encoding="utf-8")


if __name__ == "__main__":
    main()
