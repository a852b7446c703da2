"""Resource estimates before allocation: triangles, texture pixels and bytes per command.

Every command estimates what it will build from its parameters alone (no mesh, no image is
made) and refuses, naming the estimate and the limit, when the memory it needs exceeds
``max_memory`` (``--max-memory`` on the command line; default :data:`DEFAULT_MAX_MEMORY_GB`).
The per-item costs are measured peaks of this package (RSS, Linux, numpy 2, usd-core 26):

* a column written as USD: 2.03 M triangles → 642 MB peak (≈ 300 B per triangle with the
  interpreter);
* the asset adds UVs (analytic charts) and one Vt array copy per mesh: counted at 2x that;
* a stone texture set: 1024² → 266 MB, 2048² → 707 MB peak (≈ 140 B per pixel, one style at a
  time).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

from ionic_usd.errors import BudgetError, ParameterError
from ionic_usd.lod import LOD_NAMES

if TYPE_CHECKING:  # pragma: no cover
    from ionic_usd.column.column import ColumnParams

__all__ = [
    "BASELINE_BYTES",
    "BYTES_PER_TEXEL",
    "BYTES_PER_TRIANGLE",
    "DEFAULT_MAX_MEMORY_GB",
    "Estimate",
    "capital_triangle_estimate",
    "check_estimate",
    "column_triangle_estimate",
    "estimate_asset",
    "estimate_city",
    "estimate_inputs",
    "estimate_render",
    "estimate_column",
    "estimate_temple",
    "input_bytes",
    "max_memory_bytes",
]

BYTES_PER_TRIANGLE = 300
BYTES_PER_TEXEL = 140
BASELINE_BYTES = 150 << 20  # interpreter, numpy, pxr
DEFAULT_MAX_MEMORY_GB = 4.0
#: bytes a city writes per temple instance and per street column (measured City.usda:
#: ~1.6 kB per temple reference with its variant selections, ~60 B per instancer point)
_CITY_BYTES_PER_TEMPLE = 2048
_CITY_BYTES_PER_COLUMN = 64


@dataclass(frozen=True)
class Estimate:
    """What a command will allocate: triangles, texture pixels and peak bytes."""

    what: str
    triangles: int = 0
    pixels: int = 0
    bytes: int = 0

    def describe(self) -> str:
        parts = []
        if self.triangles:
            parts.append(f"{self.triangles:,} triangles")
        if self.pixels:
            parts.append(f"{self.pixels:,} texture pixels")
        counts = f" ({', '.join(parts)})" if parts else ""
        return f"{self.what} needs about {_gb(self.bytes)} of memory{counts}"


def _gb(n: float) -> str:
    return f"{n / 1e9:.1f} GB" if n >= 1e8 else f"{n / 1e6:.0f} MB"


def max_memory_bytes(gb: float | None) -> int:
    """The limit in bytes for ``--max-memory GB`` (None: the default)."""
    if gb is None:
        gb = DEFAULT_MAX_MEMORY_GB
    if (
        isinstance(gb, bool)
        or not isinstance(gb, int | float)
        or not math.isfinite(gb)
        or not 0.1 <= gb <= 1 << 20
    ):
        raise ParameterError("--max-memory", gb, "a number of GB in [0.1, 1048576]")
    return int(gb * 1e9)


def check_estimate(est: Estimate, max_memory_gb: float | None = None) -> Estimate:
    """Raise :class:`BudgetError` (naming the estimate and the limit) if ``est`` exceeds it."""
    limit = max_memory_bytes(max_memory_gb)
    if est.bytes > limit:
        raise BudgetError(
            f"{est.describe()}; the limit is {_gb(limit)} (--max-memory GB "
            "raises it on a machine with more memory)"
        )
    return est


# -- triangles from parameters (nothing is built) --------------------------------------------
def _capital_parts(
    spiral_samples: int, ring_segments: int, bolster_rows: int, scroll_rings: int
) -> tuple[int, int]:
    # fit of low/medium/high with S1 and S2: body 48·spiral + 16·ring, bolsters
    # 4·ring·(rows + scroll rings)
    return (
        48 * spiral_samples + 16 * ring_segments,
        4 * ring_segments * (bolster_rows + scroll_rings),
    )


def capital_triangle_estimate(
    spiral_samples: int, ring_segments: int, bolster_rows: int, scroll_rings: int = 5
) -> int:
    """Triangles of a capital (body + bolsters); exact for the named LODs with the S1 and S2
    scrolls, an upper bound within a few percent elsewhere (tests/test_resources.py)."""
    return sum(_capital_parts(spiral_samples, ring_segments, bolster_rows, scroll_rings))


def _part_triangles(
    params: ColumnParams, *, base: str | None = None, scroll: str | None = None
) -> tuple[int, int, int, int]:
    """(base, shaft, capital body, bolsters) triangles for ``params`` — from parameters."""
    from ionic_usd.column.base import base_triangle_estimate
    from ionic_usd.column.shaft import shaft_triangle_estimate
    from ionic_usd.grammar.scroll import resolve_scroll

    shaft = params.shaft_params()
    shaft_t = shaft_triangle_estimate(shaft)
    # the shaft's flute-ring vertex count is the base's segment count: a huge one would make
    # even the base's profile estimate slow, and is refused anyway
    if shaft.ring_segments > 1_000_000:
        base_t = 2 * shaft.ring_segments
    else:
        base_t = base_triangle_estimate(params.base_params(base))
    cap = params.capital_params(scroll)
    body, bolsters = _capital_parts(
        cap.spiral_samples,
        cap.ring_segments,
        cap.bolster_rows,
        len(resolve_scroll(cap.scroll).rings),
    )
    return base_t, shaft_t, body, bolsters


def column_triangle_estimate(
    params: ColumnParams, *, base: str | None = None, scroll: str | None = None
) -> int:
    """Triangles :func:`ionic_usd.column.column.build_column` will emit for ``params``."""
    return sum(_part_triangles(params, base=base, scroll=scroll))


def estimate_column(params: ColumnParams) -> Estimate:
    t = column_triangle_estimate(params)
    return Estimate("the column", t, 0, BASELINE_BYTES + BYTES_PER_TRIANGLE * t)


def _texture_bytes(size: int) -> tuple[int, int]:
    return size * size, BYTES_PER_TEXEL * size * size


def estimate_asset(
    params: ColumnParams,
    texture_size: int,
    *,
    lods=None,
    bases=None,
    scrolls=None,
    flutes=None,
    forms: int = 3,
    capitals: int = 2,
    volutes: int = 2,
    what: str = "the asset",
) -> Estimate:
    """Every mesh of the column asset (per LOD: each base, a shaft per flute count, one
    capital solid per scroll, capital and volute variant — body and bolsters united;
    ``forms`` times, the cut forms counted as full ones, an upper bound) and one stone
    texture set at a time."""
    from ionic_usd.blueprint.column_asset import BASE_VARIANTS, FLUTE_VARIANTS, SCROLL_VARIANTS

    tris = 0
    for lod in lods or LOD_NAMES:
        p = params.with_lod(lod)
        tris += sum(_part_triangles(p, base=b)[0] for b in bases or BASE_VARIANTS)
        for n in flutes or tuple(FLUTE_VARIANTS.values()):
            shaft = dataclasses.replace(p.shaft, flutes=n, flute_angle=0.8 * 360.0 / n)
            tris += _part_triangles(dataclasses.replace(p, shaft=shaft))[1]
        tris += (
            capitals
            * volutes
            * sum(
                _part_triangles(p)[2] + _part_triangles(p, scroll=s)[3]
                for s in scrolls or SCROLL_VARIANTS
            )
        )
    tris *= forms
    px, tex = _texture_bytes(texture_size)
    return Estimate(what, tris, 3 * px, BASELINE_BYTES + 2 * BYTES_PER_TRIANGLE * tris + tex)


def estimate_temple(params: ColumnParams, texture_size: int, cuboids: int = 0) -> Estimate:
    """The temple: its column asset plus the cuboid parts (12 triangles each)."""
    a = estimate_asset(params, texture_size, what="the temple")
    t = a.triangles + 12 * cuboids
    return Estimate("the temple", t, a.pixels, a.bytes + BYTES_PER_TRIANGLE * 12 * cuboids)


def estimate_city(rows: int, cols: int, street_columns: int) -> Estimate:
    """A city layer: bytes of City.usda in memory while authored and written (x3)."""
    b = 3 * (rows * cols * _CITY_BYTES_PER_TEMPLE + street_columns * _CITY_BYTES_PER_COLUMN)
    return Estimate(
        f"the city ({rows * cols:,} temples, {street_columns:,} street columns)",
        0,
        0,
        BASELINE_BYTES + b,
    )


#: a framebuffer pixel: the resolved RGBA, its read-back and the PNG rows (measured 19 B/px:
#: 2048² without MSAA, llvmpipe); each MSAA sample adds a colour and a depth value
_BYTES_PER_PIXEL = 20
_BYTES_PER_SAMPLE = 8
#: decoded bytes per byte of input file (a crate file holds a triangle in ~18 B, numpy and
#: Vt hold it in ~300 B; a text point cloud holds a point in ~30 B, the fit's arrays, copies
#: and KD-tree about 16x that)
INPUT_EXPANSION = 16


def estimate_render(width: int, height: int, samples: int) -> Estimate:
    """A preview: its framebuffers (the scene's own meshes were bounded when written)."""
    px = width * height
    per_px = _BYTES_PER_PIXEL + _BYTES_PER_SAMPLE * max(samples, 1)
    return Estimate(
        f"a {width}x{height} picture with {samples} samples", 0, 0, BASELINE_BYTES + px * per_px
    )


def input_bytes(*paths: object) -> int:
    """Bytes on disk of the given files; a USD file counts with every USD layer of its
    folder tree (the layers it may reference: a temple's or a city's parts)."""
    from pathlib import Path

    total = 0
    for p in paths:
        if p is None:
            continue
        path = Path(str(p))
        if not path.is_file():
            continue
        total += path.stat().st_size
        if path.suffix.lower() in (".usd", ".usda", ".usdc"):
            total += _usd_layers_beside(path)
    return total


def _usd_layers_beside(path: object, cap: int = 20_000) -> int:
    """Bytes of the other USD layers under ``path``'s folder (the first ``cap`` entries)."""
    import itertools
    from pathlib import Path

    p = Path(str(path))
    total = 0
    for q in itertools.islice(p.parent.rglob("*"), cap):
        if q != p and q.suffix.lower() in (".usd", ".usda", ".usdc") and q.is_file():
            total += q.stat().st_size
    return total


def estimate_inputs(what: str, *paths: object) -> Estimate:
    """A command whose allocation follows what it reads (export, fit, evaluate)."""
    return Estimate(what, 0, 0, BASELINE_BYTES + INPUT_EXPANSION * input_bytes(*paths))
