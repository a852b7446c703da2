"""Evaluation reports: a text table like the paper's Table 6, JSON, and overlay plots (Fig. 9).

JSON layout written by :func:`write_json` (schema ``"ionic_usd.evaluate/1"``)::

    {
      "schema": "ionic_usd.evaluate/1",
      "unit": "m",                       # unit of every length and distance
      "parts": {
        "<part>": {
          "nodes_a": int, "nodes_b": int,            # node counts (a = reference)
          "length_a": float, "length_b": float,      # polyline lengths
          "mean_length": float,                      # their mean, the % denominator
          "hausdorff": float,         # node-to-curve, symmetric (paper: "weak Fréchet")
          "node_hausdorff": float,    # node-to-node, symmetric (paper: "Hausdorff")
          "average_error": float,     # mean node-to-curve distance, both directions pooled
          "discrete_frechet": float,  # Eiter-Mannila
          "frechet": float,           # continuous, Alt-Godau
          "<measure>_pct": float | null,   # each measure as % of mean_length
          "alignment": {              # only when an Alignment was given for the part
            "translation": [float, ...], "mirrored": bool,
            "hausdorff_before": float, "hausdorff_after": float
          }
        }
      },
      "metadata": {...}               # free-form, as passed (must be JSON-serialisable)
    }

All files are written atomically: to a temporary file in the destination folder, then
``os.replace``-d over the target, so readers never see a half-written file.
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import IO, Any

import numpy as np

from ionic_usd.errors import ParameterError
from ionic_usd.evaluate.metrics import CurveComparison, point_to_polyline_distances
from ionic_usd.evaluate.polyline import as_curve
from ionic_usd.evaluate.reference import Alignment

__all__ = [
    "SCHEMA",
    "format_table",
    "plot_overlay",
    "write_atomically",
    "write_json",
    "write_fit_json",
    "write_curves_csv",
]

SCHEMA = "ionic_usd.evaluate/1"

# (field, column title) in the order of the paper's Table 6, then the true Fréchet measures.
_COLUMNS = (
    ("hausdorff", "node-to-curve (paper: weak Fréchet)"),
    ("node_hausdorff", "node-to-node (paper: Hausdorff)"),
    ("average_error", "avg error"),
    ("discrete_frechet", "discrete Fréchet"),
    ("frechet", "Fréchet"),
)


def write_atomically(path: str | Path, write: Callable[[IO[bytes]], object]) -> Path:
    """Write a file through ``write(binary file)`` atomically (:func:`ionic_usd.io.atomic_path`:
    a temporary sibling, synced, renamed over ``path``; nothing is left on failure)."""
    from ionic_usd.io import atomic_path

    path = Path(path)
    with atomic_path(path) as tmp, open(tmp, "wb") as fh:
        write(fh)
    return path


def _cell(value: float, pct: float, unit: str, digits: int) -> str:
    pct_text = "n/a" if math.isnan(pct) else f"{pct:.2f}%"
    return f"{value:.{digits}f} {unit} ({pct_text})"


def format_table(rows: Mapping[str, CurveComparison], *, unit: str = "m", digits: int = 4) -> str:
    """Plain-text table in the shape of the paper's Table 6.

    One line per part: node counts (a + b), curve lengths (a + b), then each measure in
    ``unit`` and as a percentage of the mean curve length. Columns marked ``*`` use the
    paper's names: "weak Fréchet" is the node-to-curve Hausdorff distance, "Hausdorff" the
    node-to-node one.

    Parameters
    ----------
    rows : mapping of str to CurveComparison
        Part name (e.g. ``"base"``) to its comparison, in display order.
    unit : str
        Label for the distances' unit.
    digits : int
        Decimals for distances.

    Returns
    -------
    str
        Lines joined with ``\\n``, ending with a footnote line.
    """
    if not rows:
        raise ParameterError("rows", rows, "at least one part")
    header = ["part", "nodes", "length", *(title for _, title in _COLUMNS)]
    body = []
    for name, c in rows.items():
        if not isinstance(c, CurveComparison):
            raise ParameterError(f"rows[{name!r}]", type(c).__name__, "a CurveComparison")
        body.append(
            [
                str(name),
                f"{c.nodes_a} + {c.nodes_b}",
                f"{c.length_a:.{digits}f} + {c.length_b:.{digits}f}",
                *(
                    _cell(getattr(c, field), c.percent(field), unit, digits)
                    for field, _ in _COLUMNS
                ),
            ]
        )
    widths = [max(len(r[k]) for r in [header, *body]) for k in range(len(header))]

    def line(cells: list[str]) -> str:
        first = cells[0].ljust(widths[0])
        rest = (c.rjust(w) for c, w in zip(cells[1:], widths[1:], strict=True))
        return "  ".join([first, *rest]).rstrip()

    rule = "  ".join("-" * w for w in widths)
    footnote = (
        "Hausdorff distances: node-to-curve counts points on edges (the paper's 'weak "
        "Fréchet'), node-to-node only nodes (the paper's 'Hausdorff', which depends on the "
        "sampling); % of the mean curve length"
    )
    return "\n".join([line(header), rule, *(line(r) for r in body), footnote])


def write_json(
    path: str | Path,
    rows: Mapping[str, CurveComparison],
    *,
    alignments: Mapping[str, Alignment] | None = None,
    metadata: Mapping[str, Any] | None = None,
    unit: str = "m",
) -> Path:
    """Write comparisons (and the alignments applied) as JSON; keys in the module docstring.

    Parameters
    ----------
    path : str or Path
    rows : mapping of str to CurveComparison
    alignments : mapping of str to Alignment, optional
        Keyed by part; each must name a part in ``rows``.
    metadata : mapping, optional
        Stored as is under ``"metadata"``.
    unit : str

    Returns
    -------
    Path
        The written file.
    """
    alignments = dict(alignments or {})
    unknown = sorted(set(alignments) - set(rows))
    if unknown:
        raise ParameterError("alignments", unknown, f"parts among {sorted(rows)}")
    parts: dict[str, Any] = {}
    for name, c in rows.items():
        if not isinstance(c, CurveComparison):
            raise ParameterError(f"rows[{name!r}]", type(c).__name__, "a CurveComparison")
        entry: dict[str, Any] = c.as_dict()
        if name in alignments:
            entry["alignment"] = alignments[name].as_dict()
        parts[str(name)] = entry
    doc = {"schema": SCHEMA, "unit": unit, "parts": parts, "metadata": dict(metadata or {})}
    try:
        text = json.dumps(doc, indent=2, ensure_ascii=False, allow_nan=False)
    except (TypeError, ValueError) as exc:
        raise ParameterError("metadata", metadata, "JSON-serialisable values") from exc
    return write_atomically(path, lambda fh: fh.write(text.encode("utf-8") + b"\n"))


def plot_overlay(
    a: np.ndarray,
    b: np.ndarray,
    path: str | Path,
    *,
    title: str | None = None,
    labels: tuple[str, str] = ("reference", "generated"),
    dpi: int = 150,
) -> Path:
    """PNG like the paper's Figure 9: the two curves, and node-to-curve distance circles.

    Left panel: both curves overlaid (reference yellow, generated red, as in the paper).
    Right panel: the curves with, at every node, a circle whose radius is that node's
    distance to the other curve (edges included) — the largest circle is the paper's
    "weak Fréchet" distance. matplotlib (Agg) is imported only here.

    Parameters
    ----------
    a, b : (n, 2), (m, 2) float
    path : str or Path
        Output ``.png``.
    title : str, optional
    labels : (str, str)
    dpi : int

    Returns
    -------
    Path
        The written file.
    """
    a = as_curve(a, "a", min_nodes=2)
    b = as_curve(b, "b", min_nodes=2)
    if a.shape[1] != 2 or b.shape[1] != 2:
        raise ParameterError("a/b", (a.shape, b.shape), "2D curves (n, 2)")
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    ra = point_to_polyline_distances(a, b)
    rb = point_to_polyline_distances(b, a)
    colours = ("#d4a500", "#d62728")
    both = np.vstack((a, b))
    span = np.ptp(both, axis=0)
    aspect = float(span[1] / span[0]) if span[0] > 0 else 1.0
    # Two equal-aspect panels side by side: size the figure to the data so it is not padded.
    fig = Figure(figsize=(11, min(max(5.5 * aspect + 1.0, 3.0), 12.0)), layout="constrained")
    FigureCanvasAgg(fig)
    left, right = fig.subplots(1, 2, sharex=True, sharey=True)
    for ax in (left, right):
        ax.plot(a[:, 0], a[:, 1], "-", color=colours[0], lw=1.2, label=labels[0])
        ax.plot(b[:, 0], b[:, 1], "-", color=colours[1], lw=1.0, label=labels[1])
        ax.set_aspect("equal", adjustable="box")
        ax.grid(True, lw=0.3, alpha=0.5)
    for pts, r, colour in ((a, ra, colours[0]), (b, rb, colours[1])):
        _distance_circles(right, pts, r, colour)
    left.legend(loc="best", fontsize=8)
    left.set_title("curves", fontsize=10)
    for ax in (left, right):
        ax.set_xlabel("x (m)")
    left.set_ylabel("y (m)")
    worst = float(max(ra.max(), rb.max()))
    right.set_title(f"node-to-curve distances (max {worst * 1000:.3g} mm)", fontsize=10)
    extent = float(np.linalg.norm(span))
    if 0 < worst < 2e-3 * extent:
        _worst_node_inset(right, a, b, ra, rb, colours, extent)
    if title:
        fig.suptitle(title)

    def write(fh: IO[bytes]) -> None:
        fig.savefig(fh, format="png", dpi=dpi)

    return write_atomically(path, write)


def write_fit_json(
    path: str | Path,
    fits: Mapping[str, Any],
    *,
    metadata: Mapping[str, Any] | None = None,
    extra: Mapping[str, Any] | None = None,
) -> Path:
    """Write fits as JSON (schema ``ionic_usd.evaluate/1``): per part its
    :meth:`~ionic_usd.evaluate.fit_core.FitResult.as_dict` — every measure and its ``_pct``,
    ``before``, ``alignment``, ``parameters``, ``model``, ``bounds_hit``, ``diameter_estimate``,
    ``resample_spacing`` and, for the volute, every model under ``models``.

    Parameters
    ----------
    path : output ``.json``
    fits : part name → FitResult
    metadata : stored under ``"metadata"``
    extra : top-level keys added as they are (e.g. a scan's ``deviation``)
    """
    doc: dict[str, Any] = {
        "schema": SCHEMA,
        "unit": "m",
        "parts": {str(k): f.as_dict() for k, f in fits.items()},
    }
    doc.update(dict(extra or {}))
    doc["metadata"] = dict(metadata or {})
    try:
        text = json.dumps(doc, indent=2, ensure_ascii=False, allow_nan=False)
    except (TypeError, ValueError) as exc:
        raise ParameterError("fit report", str(exc), "finite, JSON-serialisable values") from exc
    return write_atomically(path, lambda fh: fh.write(text.encode("utf-8") + b"\n"))


def write_curves_csv(path: str | Path, curves: Mapping[str, Mapping[str, np.ndarray]]) -> Path:
    """Write curves as CSV rows ``part,curve,index,x,y`` (metres, full precision).

    Parameters
    ----------
    path : output ``.csv``
    curves : part → curve name → (n, 2) float
    """
    lines = ["part,curve,index,x,y"]
    for part, named in curves.items():
        for name, c in named.items():
            c = as_curve(c, f"{part}/{name}", min_nodes=1)
            lines.extend(
                f"{part},{name},{i},{x!r},{y!r}" for i, (x, y) in enumerate(c[:, :2].tolist())
            )
    text = "\n".join(lines) + "\n"
    return write_atomically(path, lambda fh: fh.write(text.encode("utf-8")))


def _distance_circles(ax, pts: np.ndarray, r: np.ndarray, colour: str) -> None:
    """At every node of ``pts`` a circle of radius ``r`` (its distance to the other curve)."""
    from matplotlib.collections import EllipseCollection

    ax.add_collection(
        EllipseCollection(
            2 * r,
            2 * r,
            np.zeros_like(r),
            units="xy",
            offsets=pts,
            offset_transform=ax.transData,
            facecolors="none",
            edgecolors=colour,
            linewidths=0.5,
            alpha=0.8,
        )
    )


def _worst_node_inset(right, a, b, ra, rb, colours, extent: float) -> None:
    """Sub-visible errors: a zoomed inset round the worst node, its scale in millimetres."""
    worst = float(max(ra.max(), rb.max()))
    k = int(np.argmax(ra)) if ra.max() >= rb.max() else int(np.argmax(rb))
    at = a[k] if ra.max() >= rb.max() else b[k]
    half = max(6.0 * worst, 1e-6 * extent)
    inset = right.inset_axes([0.58, 0.5, 0.4, 0.4])
    inset.plot(a[:, 0], a[:, 1], "-o", color=colours[0], lw=1.2, ms=2)
    inset.plot(b[:, 0], b[:, 1], "-o", color=colours[1], lw=1.0, ms=2)
    inset.set_xlim(at[0] - half, at[0] + half)
    inset.set_ylim(at[1] - half, at[1] + half)
    inset.set_aspect("equal", adjustable="box")
    inset.tick_params(labelsize=6)
    ticks = np.array([-half, 0.0, half]) * 0.8
    inset.set_xticks(at[0] + ticks, [f"{t * 1000:+.2g}" for t in ticks])
    inset.set_yticks(at[1] + ticks, [f"{t * 1000:+.2g}" for t in ticks])
    inset.set_title(f"worst node, ×{extent / (2 * half):.0f} (mm)", fontsize=7)
    right.indicate_inset_zoom(inset, edgecolor="0.3")
