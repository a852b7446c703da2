"""Evaluation: curve similarity measures, reference curves, sections of the model, automatic
fitting and reports (paper §VII).

The names below are imported on first use (``from ionic_usd.evaluate import compare`` works
as before): the measures need numba and scipy, which the command line must not load to parse
its flags.
"""

from __future__ import annotations

from ionic_usd.lazy import lazy_attributes

#: public name → the module that defines it
_NAMES = {
    "BaseLayout": "ionic_usd.evaluate.fit",
    "FitResult": "ionic_usd.evaluate.fit",
    "densify": "ionic_usd.evaluate.fit",
    "fit_base": "ionic_usd.evaluate.fit",
    "fit_shaft": "ionic_usd.evaluate.fit",
    "fit_volute": "ionic_usd.evaluate.fit",
    "fit_shaft_section": "ionic_usd.evaluate.fit_shaft",
    "fluted_section": "ionic_usd.evaluate.fit_shaft",
    "fit_column_scan": "ionic_usd.evaluate.fit_scan",
    "ScanFit": "ionic_usd.evaluate.fit_scan",
    "read_scan": "ionic_usd.evaluate.scan_io",
    "suggest_base_layout": "ionic_usd.evaluate.fit",
    "base_section": "ionic_usd.evaluate.sections",
    "section_from_usd": "ionic_usd.evaluate.sections",
    "shaft_cross_section_at": "ionic_usd.evaluate.sections",
    "shaft_silhouette_section": "ionic_usd.evaluate.sections",
    "slice_mesh": "ionic_usd.evaluate.sections",
    "volute_section": "ionic_usd.evaluate.sections",
    "Alignment": "ionic_usd.evaluate.reference",
    "align": "ionic_usd.evaluate.reference",
    "format_table": "ionic_usd.evaluate.report",
    "plot_overlay": "ionic_usd.evaluate.report",
    "read_csv_curve": "ionic_usd.evaluate.reference",
    "read_reference": "ionic_usd.evaluate.reference",
    "read_svg_curve": "ionic_usd.evaluate.reference",
    "write_json": "ionic_usd.evaluate.report",
    "CurveComparison": "ionic_usd.evaluate.metrics",
    "average_error": "ionic_usd.evaluate.metrics",
    "compare": "ionic_usd.evaluate.metrics",
    "curve_length": "ionic_usd.evaluate.metrics",
    "densify_curve": "ionic_usd.evaluate.metrics",
    "directed_hausdorff_distance": "ionic_usd.evaluate.metrics",
    "discrete_frechet_distance": "ionic_usd.evaluate.metrics",
    "frechet_distance": "ionic_usd.evaluate.metrics",
    "hausdorff_distance": "ionic_usd.evaluate.metrics",
    "node_hausdorff_distance": "ionic_usd.evaluate.metrics",
    "paper_weak_frechet": "ionic_usd.evaluate.metrics",
    "point_to_polyline_distances": "ionic_usd.evaluate.metrics",
    "resample": "ionic_usd.evaluate.metrics",
}

#: Measures a fit can minimise (names of :class:`CurveComparison` fields). Defined here, not
#: in :mod:`~ionic_usd.evaluate.fit_core`, so the command line lists them without scipy.
FIT_MEASURES = ("hausdorff", "average_error", "discrete_frechet", "frechet")

__all__ = ["FIT_MEASURES", *_NAMES]


__getattr__, __dir__ = lazy_attributes(__name__, _NAMES, globals())
