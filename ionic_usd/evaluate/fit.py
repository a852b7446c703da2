"""Automatic fitting of model parameters to reference curves — the step beyond the paper.

The paper tuned its parameters by hand; here scipy does it. The machinery is in
:mod:`.fit_core` (objective, three-stage optimiser, result), one module per part
(:mod:`.fit_volute`, :mod:`.fit_base`, :mod:`.fit_shaft`) and whole columns from scans
(:mod:`.fit_scan`). This module gathers their public names.
"""

from __future__ import annotations

from ionic_usd.evaluate.fit_base import (
    BaseLayout,
    base_grammar_string,
    fit_base,
    suggest_base_layout,
)
from ionic_usd.evaluate.fit_core import (
    FIT_MEASURES,
    FitResult,
    compare_aligned,
    densify,
    orient_like,
)
from ionic_usd.evaluate.fit_shaft import fit_shaft
from ionic_usd.evaluate.fit_volute import fit_volute

__all__ = [
    "FIT_MEASURES",
    "FitResult",
    "BaseLayout",
    "fit_volute",
    "fit_base",
    "fit_shaft",
    "suggest_base_layout",
    "base_grammar_string",
    "orient_like",
    "compare_aligned",
    "densify",
]
