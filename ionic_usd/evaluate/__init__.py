"""Evaluation: curve similarity measures, reference curves and reports (paper §VII)."""

from __future__ import annotations

from ionic_usd.evaluate.metrics import (
    CurveComparison,
    average_error,
    compare,
    curve_length,
    densify_curve,
    directed_hausdorff_distance,
    discrete_frechet_distance,
    frechet_distance,
    hausdorff_distance,
    node_hausdorff_distance,
    paper_weak_frechet,
    point_to_polyline_distances,
    resample,
)
from ionic_usd.evaluate.reference import (
    Alignment,
    align,
    read_csv_curve,
    read_reference,
    read_svg_curve,
)
from ionic_usd.evaluate.report import format_table, plot_overlay, write_json

__all__ = [
    "Alignment",
    "align",
    "format_table",
    "plot_overlay",
    "read_csv_curve",
    "read_reference",
    "read_svg_curve",
    "write_json",
    "CurveComparison",
    "average_error",
    "compare",
    "curve_length",
    "densify_curve",
    "directed_hausdorff_distance",
    "discrete_frechet_distance",
    "frechet_distance",
    "hausdorff_distance",
    "node_hausdorff_distance",
    "paper_weak_frechet",
    "point_to_polyline_distances",
    "resample",
]
