"""The Ionic capital (paper section VI, Tables 4–5, Figure 5; SPEC §3).

Frame: metres, Y up; the origin is the centre of the shaft's top circle (radius ``top_radius``,
given by the caller); the front faces +Z. Parts, each a set of closed, outward-wound shells:

* **echinus** — the round cushion (an ovolo: a convex quarter ellipse revolved about Y) from the
  shaft's top radius out by ``echinus_projection`` over ``echinus_height``;
* **volutes** — four (front/rear × right/left), see :mod:`ionic_usd.column.volute`: a backing
  disc (channel floor), the raised spiral band and the eye boss; the right-front one is built,
  the others are mirror images (``transform`` with a reflection reverses their winding);
* **canales** — the front and rear plates joining the two volutes of a face under the abacus;
  the band's straight continuation (the *spiral margin*) runs along their top;
* **bolsters** — the scroll bodies (pulvini) joining front and rear volutes along Z, lofted
  from the ring grammar (:mod:`ionic_usd.grammar.scroll`) and centred on the eye axis;
* **abacus** — the thin slab on top.

The corner columns' **angle capital** is built by :mod:`ionic_usd.column.angle_capital`; the
parameters, layout and shared parts are in :mod:`ionic_usd.column.capital_body`.

The paper's five general parameters, as read here (its Figure 5 is not in the text):

* ``capital_length`` — X extent of the volute group, outer edge of the left volute to the outer
  edge of the right one; it places the eyes: ``eye_x = length/2 − (volute's +X extent)``;
* ``capital_width`` — Z extent of the volute group, front band face to rear band face;
* ``spiral_margin`` — length of the straight band continuing each volute's top end towards the
  axis (the canalis' upper edge); cut at the centre plane, where the two margins meet (they
  overlap by a :func:`~ionic_usd.column.capital_body.seat_depth`, see below);
* ``scroll_position_y`` — height of the eye centres above the capital's bottom;
* ``capital_position_y`` — height of the capital's bottom above the shaft top.

Vertical layout: echinus ``[0, echinus_height]``; the abacus rests on the volutes' top (the band's
top end), ``y_abacus = max(scroll_position_y + volute top extent, echinus_height)``; everything is
lifted by ``capital_position_y``. :func:`capital_height` is the abacus' top.

Parts that rest on one another are sunk into each other by a *seat*
(:func:`~ionic_usd.column.capital_body.seat_depth`, 0.75 mm for Portunus): the band and eye into
the disc and canalis, the bolster ends into the discs, the canales' tops and the margins' far
ends up into the abacus, the meeting margins across the centre plane. Faces that only touch are
coincident planes for the union, which manifold3d may keep as a zero-thickness slit inside the
solid.

Defaults (Vitruvius III.5.5–7 for the Temple of Portunus, D = 0.95 m, part = D/18): abacus
(D + D/18) square and 1½ parts thick; volutes 8 parts high with the eye ½ part above the shaft
top (so they hang 3 parts below it) and on the *cathetus* 1½ parts inside the abacus' ends;
echinus 2½ parts high projecting 1½ parts; capital width D.
"""

from __future__ import annotations

import math

import numpy as np

from ionic_usd.column.angle_capital import build_angle_capital
from ionic_usd.column.capital_body import (
    CAPITAL_PARAMETER_DOCS,
    CapitalLayout,
    CapitalParams,
    CapitalParts,
    abacus_mesh,
    bolster_mesh,
    bolster_profile,
    canalis_bottom,
    capital_height,
    capital_layout,
    echinus_mesh,
    rim_radius,
    seat_depth,
)
from ionic_usd.column.solids import MIRROR_X, MIRROR_Z, box_mesh, rigid
from ionic_usd.column.volute_solid import build_volute
from ionic_usd.errors import ParameterError
from ionic_usd.geometry.mesh import Mesh

__all__ = [
    "CapitalParams",
    "CapitalParts",
    "CapitalLayout",
    "CAPITAL_PARAMETER_DOCS",
    "capital_layout",
    "capital_height",
    "build_capital",
    "capital_mesh",
    "bolster_profile",
]


def build_capital(
    p: CapitalParams | None = None, *, top_radius: float, angle: bool = False
) -> CapitalParts:
    """Build the Ionic capital's parts.

    Parameters
    ----------
    p : CapitalParams (defaults: Vitruvius / Portunus)
    top_radius : radius of the shaft's top circle $c (m), where the echinus starts
    angle : the angle (corner) capital of :mod:`ionic_usd.column.angle_capital`: outer faces +Z
        and +X each a full volute face with its canalis, the corner volute turned 45° onto the
        diagonal, the inner faces −X and −Z bolsters mitred at the inner corner.
        ``volutes``: front-left, corner, side-rear; ``canales``: front, side; ``bolsters``:
        left, rear; ``cores``: the body under the abacus.

    Returns
    -------
    CapitalParts, every mesh a union of closed, outward-wound triangle shells with normals.
    """
    p = p or CapitalParams()
    if (
        isinstance(top_radius, bool)
        or not isinstance(top_radius, int | float)
        or not math.isfinite(top_radius)
        or top_radius <= 0
    ):
        raise ParameterError(
            "top_radius", top_radius, "a length > 0 (the shaft's $c)", context="capital"
        )
    lay = capital_layout(p)
    if angle:
        return build_angle_capital(p, lay, float(top_radius)).lifted(p.capital_position_y)
    seat = seat_depth(p)
    margin = lay.margin
    if lay.margin_gap < seat:
        # margins that would meet (or all but meet) on the centre plane cross it by a seat:
        # two band ends touching there would be coincident faces for the union
        margin += lay.margin_gap + seat
    vol = build_volute(
        p.volute,
        samples=p.spiral_samples,
        eye_segments=p.ring_segments,
        relief_depth=p.relief_depth,
        slab_depth=p.slab_depth,
        margin=margin,
        seat=seat,
        rim=rim_radius(p, lay),
        rim_segments=p.ring_segments,  # the bolster's
    )
    fr = rigid(vol, np.eye(3), (lay.eye_x, lay.eye_y, lay.face_z), "volute_front_right")
    fl = rigid(fr, MIRROR_X, name="volute_front_left")
    rr = rigid(fr, MIRROR_Z, name="volute_rear_right")
    rl = rigid(fl, MIRROR_Z, name="volute_rear_left")
    slab_front = lay.face_z - p.relief_depth
    front = box_mesh(
        (-lay.eye_x, canalis_bottom(p, lay), lay.back_z),
        (lay.eye_x, lay.abacus_y + seat, slab_front),
        "canalis_front",
    )
    rear = rigid(front, MIRROR_Z, name="canalis_rear")
    br = rigid(
        bolster_mesh(p, 2 * lay.back_z, lay.total_radius, extend=seat, lead=seat),
        np.eye(3),
        (lay.eye_x, lay.eye_y, lay.back_z),
        "bolster_right",
    )
    bl = rigid(br, MIRROR_X, name="bolster_left")
    parts = CapitalParts(
        abacus_mesh(p, lay),
        echinus_mesh(p, float(top_radius), p.ring_segments),
        (fr, fl, rr, rl),
        (front, rear),
        (br, bl),
    )
    return parts.lifted(p.capital_position_y)


def capital_mesh(
    p: CapitalParams | None = None, *, top_radius: float, name: str = "capital", angle: bool = False
) -> Mesh:
    """All capital parts united into one closed solid (manifold3d boolean union)."""
    from ionic_usd.geometry.boolean import union

    parts = build_capital(p, top_radius=top_radius, angle=angle)
    return union(list(parts.as_dict().values()), name=name)
