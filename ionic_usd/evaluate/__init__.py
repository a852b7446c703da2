"""Evaluation: curve similarity measures, reference curves, sections of the model, automatic
fitting and reports (paper §VII)."""

from __future__ import annotations

from ionic_usd.evaluate.fit import (
    FIT_MEASURES,
    BaseLayout,
    FitResult,
    densify,
    fit_base,
    fit_shaft,
    fit_volute,
    suggest_base_layout,
)
from ionic_usd.evaluate.fit_scan import ScanFit, fit_column_scan
from ionic_usd.evaluate.fit_shaft import fit_shaft_section, fluted_section
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
from ionic_usd.evaluate.scan_io import read_scan
from ionic_usd.evaluate.sections import (
    base_section,
    section_from_usd,
    shaft_cross_section_at,
    shaft_silhouette_section,
    slice_mesh,
    volute_section,
)

__all__ = [
    "FIT_MEASURES",
    "BaseLayout",
    "FitResult",
    "densify",
    "fit_base",
    "fit_shaft",
    "fit_volute",
    "fit_shaft_section",
    "fluted_section",
    "fit_column_scan",
    "ScanFit",
    "read_scan",
    "suggest_base_layout",
    "base_section",
    "section_from_usd",
    "shaft_cross_section_at",
    "shaft_silhouette_section",
    "slice_mesh",
    "volute_section",
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
