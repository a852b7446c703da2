"""The angle (corner) capital of the Temple of Portunus' corner columns.

Frame as :mod:`ionic_usd.column.capital` (metres, Y up, origin at the shaft's top centre); the
two **outer faces** are +Z and +X, the **inner faces** −X and −Z. The classical solution (the
Temple of Athena Nike, the Erechtheion's porches, Bassae and the Temple of Portunus itself):

* each outer face is a full volute face: its own volute at the face's inner end (+Z: the
  front-left volute at x = −eye_x; +X: its mirror image in the diagonal plane x = z, at
  z = −eye_x), a canalis plate running to the corner and the volute's band continued along the
  canalis' top as the spiral margin (the listel), right into the corner volute;
* the **corner volute** is shared by both outer faces: the front-right volute turned 45° about
  its eye's vertical so that its face looks along the outer diagonal (1, 0, 1)/√2, its eye on
  the diagonal a little outside the corner of the two face planes (:func:`corner_eye`). The two
  canalis plates meet in an L whose outer edge is buried in its disc, and both listels end in
  its band's top, so from either outer face the canalis runs into the volute seen at 45°;
* each inner face shows a bolster (pulvinus) as a normal capital's side does: one behind the
  front-left volute running along −Z, one behind the side volute running along −X, with the
  scroll grammar's rings from the volute (p = 0) to the point where the two bolster axes cross
  (p = 1); there they meet in a mitre on the inner diagonal plane x = z, like two mouldings
  round a corner;
* the echinus (the same ovolo as the normal capital's) runs under the canales as a moulding;
  a core block fills the body between the canales, the bolsters and the abacus.

The parts overlap one another (never touching in a lone edge or vertex) and are united into one
closed solid by :func:`ionic_usd.geometry.boolean.union`.
"""

from __future__ import annotations

import math

import numpy as np

from ionic_usd.column.capital_body import (
    CapitalLayout,
    CapitalParams,
    CapitalParts,
    abacus_mesh,
    bolster_mesh,
    canalis_bottom,
    capital_layout,
    echinus_mesh,
    seat_depth,
)
from ionic_usd.column.solids import MIRROR_X, SWAP_XZ, box_mesh, rigid, rot_y
from ionic_usd.column.volute import volute_curve
from ionic_usd.column.volute_solid import build_volute
from ionic_usd.geometry.mesh import Mesh

__all__ = [
    "build_angle_capital",
    "corner_eye",
    "CORNER_OUT",
    "MITRE_OVERLAP",
    "CORNER_LIFT",
]

#: how far (fraction of ``relief_depth``) the corner volute's band face lies outside the corner
#: of the two outer band planes, so the listels' corner ends inside its band, not on its face
CORNER_OUT = 0.85
#: the two bolsters overlap by this much (m) across the mitre plane (a shared face would be
#: two nearly coincident cut caps: slivers)
MITRE_OVERLAP = 2e-3
#: the corner volute is lifted this much (m) into the abacus: an overlap, not a tangent touch
CORNER_LIFT = 1e-3


def corner_eye(p: CapitalParams, lay: CapitalLayout | None = None) -> np.ndarray:
    """(3,) float: the corner volute's eye centre (capital frame before
    ``capital_position_y``); x = z on the outer diagonal, its band face ⊥ (1, 0, 1)."""
    lay = lay or capital_layout(p)
    e = lay.face_z + CORNER_OUT * p.relief_depth / math.sqrt(2.0)
    return np.array([e, lay.eye_y + CORNER_LIFT, e])


def build_angle_capital(p: CapitalParams, lay: CapitalLayout, top_radius: float) -> CapitalParts:
    """The angle capital's parts (module docstring), before ``capital_position_y``.

    Returns
    -------
    CapitalParts: ``volutes`` front-left, corner, side-rear; ``canales`` front, side;
    ``bolsters`` left, rear; ``cores`` the body under the abacus.
    """
    from ionic_usd.geometry.boolean import union
    from ionic_usd.geometry.clip import clip_mesh

    r, slab, seat = p.relief_depth, p.slab_depth, seat_depth(p)
    top_dx = float(volute_curve(p.volute, 2)[-1, 0]) - p.volute.offset_x

    def volute(margin: float) -> Mesh:
        return build_volute(
            p.volute,
            samples=p.spiral_samples,
            eye_segments=p.ring_segments,
            relief_depth=r,
            slab_depth=slab,
            margin=margin,
            seat=seat,
        )

    # the +Z face's own volute (front-left), its margin running along the canalis' top to
    # half a relief past the side face's band plane, inside the corner volute's band
    reach = lay.face_z + 0.5 * r
    right = volute(lay.eye_x + top_dx + reach)
    fl = rigid(
        rigid(right, np.eye(3), (lay.eye_x, lay.eye_y, lay.face_z)),
        MIRROR_X,
        name="volute_front_left",
    )
    side = rigid(fl, SWAP_XZ, name="volute_side_rear")  # the +X face's, at z = −eye_x
    # the corner volute: the front-right one (a short margin into the listels' corner) turned
    # 45° about its eye's vertical onto the outer diagonal; its disc, band and eye are united
    # first, while their touching faces are still exactly coplanar
    corner = rigid(union([volute(r)]), rot_y(45.0), corner_eye(p, lay), "volute_corner")
    # the canalis plates: an L whose outer corner edge is buried in the corner volute's disc
    slab_front = lay.face_z - r
    lo = canalis_bottom(p, lay)
    front = box_mesh(
        (-lay.eye_x, lo, lay.back_z), (slab_front, lay.abacus_y + seat, slab_front), "canalis_front"
    )
    side_canalis = rigid(front, SWAP_XZ, name="canalis_side")
    # the core: between the canales' backs (into them by half a slab), the bolster axes (1 cm
    # inside them), the echinus' top and the abacus (into it by half its height)
    inner = -lay.eye_x + 0.01
    outer = lay.back_z + 0.5 * slab
    core = box_mesh(
        (inner, p.echinus_height, inner),
        (outer, lay.abacus_y + 0.5 * p.abacus_height, outer),
        "core",
    )
    # the bolsters: grammar from the volute's back (p = 0) to the crossing of the two bolster
    # axes (p = 1), carried on past it and cut by the mitre plane x − z = overlap
    length = lay.back_z + lay.eye_x
    reach_out = lay.total_radius * max(1.0, max(g.radius for g in p.scroll_grammar.rings))
    bol = bolster_mesh(
        p,
        length,
        lay.total_radius,
        extend=reach_out + 2 * MITRE_OVERLAP + 0.01,
        lead=seat,
        name="bolster_left",
    )
    bol = rigid(bol, np.eye(3), (-lay.eye_x, lay.eye_y, lay.back_z))
    bl = clip_mesh(bol, (MITRE_OVERLAP, 0.0, 0.0), (-1.0, 0.0, 1.0), name="bolster_left")
    br = rigid(bl, SWAP_XZ, name="bolster_rear")
    return CapitalParts(
        abacus_mesh(p, lay),
        echinus_mesh(p, top_radius, p.ring_segments),
        (fl, corner, side),
        (front, side_canalis),
        (bl, br),
        (core,),
    )
