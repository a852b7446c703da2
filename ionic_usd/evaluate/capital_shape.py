"""The capital's shape as the scan fit sees it: the parameters it frees
(:data:`PROPORTIONS`, their bounds and starting values), the capital they make
(:func:`proportioned`) and the measures it reports (:func:`fitted_values`); the fit itself
is :mod:`ionic_usd.evaluate.scan_capital`."""

from __future__ import annotations

import numpy as np

from ionic_usd.column.capital import CapitalParams
from ionic_usd.evaluate.scan_volute import with_growth

__all__ = [
    "ACTIVE",
    "HI",
    "KEPT",
    "LO",
    "PROPORTIONS",
    "X0",
    "XSCALE",
    "fitted_values",
    "proportioned",
]

#: The fitted shape's parameters (:func:`proportioned`): the volute's size factor, its eyes'
#: height and half-spacing offsets (parts of D/18), then factors on the description's
#: capital width (the volute faces' distance), bolster rings' radii, echinus height and
#: projection, abacus side and abacus thickness.
PROPORTIONS = (
    "volute_scale",
    "eye_dy_parts",
    "eye_dx_parts",
    "capital_width",
    "bolster_radius",
    "echinus_height",
    "echinus_projection",
    "abacus_side",
    "abacus_height",
    "volute_growth",
    "bolster_belt",
    "eye_offset_x",
    "eye_offset_y",
    "relief_depth",
    "volute_turns",
    "band_width",
    "band_start",
)
LO = np.array(
    [0.45, -4.0, -4.0, 0.6, 0.4, 0.4, 0.0, 0.8, 0.5, 0.72, 0.0, -0.4, -0.4, 0.3, 2.4, 0.4, 0.1]
)
HI = np.array(
    [1.25, 4.0, 4.0, 1.3, 2.0, 2.0, 2.5, 1.4, 1.6, 0.98, 2.0, 0.4, 0.4, 2.0, 3.6, 1.6, 1.0]
)
#: what the fit keeps from the description (the scale and the factors above aside)
KEPT = (
    "volute's start angle and the band's growth angle (increasing_max); the centred arcs' "
    "construction (arc_square, arc_ratio)",
    "scroll ring positions",
    "spiral_margin",
    "slab_depth",
)
X0 = np.array(
    [1.0, 0.0, 0.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, np.nan, 1.0, 0.0, 0.0, 1.0, np.nan, 1.0, np.nan]
)
XSCALE = np.array(
    [0.05, 0.5, 0.5, 0.05, 0.1, 0.1, 0.2, 0.05, 0.1, 0.05, 0.2, 0.05, 0.05, 0.1, 0.1, 0.1, 0.1]
)
#: the volute's growth is the log spiral's (the centred arcs have their own construction)
ACTIVE = {
    "log_spiral": np.arange(len(PROPORTIONS)),
    "centred_arcs": np.array([k for k in range(len(PROPORTIONS)) if k != 9]),
}


def proportioned(cap: CapitalParams, model: str, x: np.ndarray) -> CapitalParams:
    """``cap`` with the volute model and the shape ``x`` (:data:`PROPORTIONS`)."""
    from ionic_usd.grammar.scroll import ScrollGrammar, ScrollRing

    part = cap.capital_width / 18.0  # the capital's width is D: a part is D/18
    vol = cap.volute.scaled(float(x[0])).with_(volute_model=model)
    turns = float(x[14]) if np.isfinite(x[14]) else vol.spiral_circuits
    if model == "log_spiral" and np.isfinite(x[9]):
        vol = with_growth(vol, float(x[9]), turns)
    elif turns != vol.spiral_circuits:
        vol = vol.with_(spiral_circuits=turns)
    if x[15] != 1.0 or np.isfinite(x[16]):  # the band's width and its start's share of it
        w = vol.thickness * float(x[15])
        share = float(x[16]) if np.isfinite(x[16]) else vol.min_thickness / vol.thickness
        vol = vol.with_(thickness=w, min_thickness=w * share)
    r = vol.capital_spiral_radius
    if x[11] != 0.0 or x[12] != 0.0:  # the eye (and the bolster's axis) off the spiral's origin
        vol = vol.with_(
            offset_x=vol.offset_x + float(x[11]) * r, offset_y=vol.offset_y + float(x[12]) * r
        )
    r0 = cap.scroll_grammar.rings[0].radius
    rings = tuple(
        ScrollRing(min((r0 + (g.radius - r0) * float(x[10])) * float(x[4]), 2.0), g.position)
        for g in cap.scroll_grammar.rings
    )
    side = float(x[7])
    return cap.with_(
        volute=vol,
        scroll=ScrollGrammar(rings) if x[4] != 1.0 or x[10] != 1.0 else cap.scroll,
        # the eye's offset moves the eye (and the bolsters on its axis), not the spiral
        scroll_position_y=cap.scroll_position_y + float(x[1]) * part + float(x[12]) * r,
        capital_length=cap.capital_length + 2.0 * float(x[2]) * part,
        capital_width=cap.capital_width * float(x[3]),
        echinus_height=cap.echinus_height * float(x[5]),
        echinus_projection=cap.echinus_projection * float(x[6]),
        abacus_length=cap.abacus_length * side,
        abacus_width=cap.abacus_width * side,
        abacus_height=cap.abacus_height * float(x[8]),
        relief_depth=cap.relief_depth * float(x[13]),
    )


def fitted_values(fitted: CapitalParams, scale: float) -> dict[str, float]:
    """The fitted capital's measures, as the report lists them."""
    from ionic_usd.column.capital_body import capital_layout
    from ionic_usd.column.volute import volute_total_radius

    return {
        "scale": scale,
        "capital_spiral_radius": fitted.volute.capital_spiral_radius,
        "capital_circle_radius": fitted.volute.capital_circle_radius,
        "scroll_position_y": fitted.scroll_position_y,
        "eye_x": float(capital_layout(fitted).eye_x),
        "eye_offset_x": fitted.volute.offset_x,
        "eye_offset_y": fitted.volute.offset_y,
        "bolster_radius": float(
            max(g.radius for g in fitted.scroll_grammar.rings) * volute_total_radius(fitted.volute)
        ),
        "relief_depth": fitted.relief_depth,
        "capital_length": fitted.capital_length,
        "capital_width": fitted.capital_width,
        "echinus_height": fitted.echinus_height,
        "echinus_projection": fitted.echinus_projection,
        "abacus_length": fitted.abacus_length,
        "abacus_width": fitted.abacus_width,
        "abacus_height": fitted.abacus_height,
    }
