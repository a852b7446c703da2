"""The Temple of Portunus column's measured figures, the one place every default derives from.

Total height 8.22 m from the base bottom to the abacus top and lower diameter 0.95 m (issue #6
brief, after Piranesi's measured drawings used by Konečný et al.). The column, capital and
volute defaults (:mod:`ionic_usd.column.column`, :mod:`~ionic_usd.column.capital_body`,
:mod:`~ionic_usd.column.volute`) are proportions of these.
"""

from __future__ import annotations

__all__ = ["PORTUNUS_HEIGHT", "PORTUNUS_LOWER_DIAMETER"]

PORTUNUS_HEIGHT = 8.22  # m, base bottom to abacus top
PORTUNUS_LOWER_DIAMETER = 0.95  # m
