"""The Ionic capital's parameters, its derived layout and the parts every capital shares.

See :mod:`ionic_usd.column.capital` for the frame, the parts and the paper's parameters as read
here; :mod:`ionic_usd.column.angle_capital` for the corner columns' capital. This module holds
:class:`CapitalParams` (with the Vitruvian defaults for the Temple of Portunus, D = 0.95 m from
:mod:`ionic_usd.column.portunus`), :func:`capital_layout`, :func:`capital_height`, the parts
container :class:`CapitalParts`, the echinus and the bolster (pulvinus) profile.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from ionic_usd.checks import check_fields
from ionic_usd.column.portunus import PORTUNUS_LOWER_DIAMETER
from ionic_usd.column.solids import box_mesh, lathe, rigid
from ionic_usd.column.volute import (
    VoluteParams,
    volute_curve,
    volute_extent,
    volute_total_radius,
)
from ionic_usd.errors import ParameterError
from ionic_usd.geometry.curves import pchip
from ionic_usd.geometry.mesh import Mesh, merge
from ionic_usd.grammar.scroll import ScrollGrammar, resolve_scroll

__all__ = [
    "CapitalParams",
    "CAPITAL_LENGTHS",
    "CapitalParts",
    "CapitalLayout",
    "CAPITAL_PARAMETER_DOCS",
    "capital_layout",
    "capital_height",
    "echinus_mesh",
    "abacus_mesh",
    "canalis_bottom",
    "bolster_profile",
    "bolster_mesh",
    "rim_radius",
]

_D = PORTUNUS_LOWER_DIAMETER
_PART = _D / 18.0


CAPITAL_PARAMETER_DOCS: dict[str, tuple[str, str, str]] = {
    "scroll": ("Table 5", "grammar", "scroll-body rings 'R<r> P<p>, …' or a preset name (S1, S2)"),
    "capital_length": ("capital length", "m", "X extent of the volutes (outer edge to edge)"),
    "capital_width": ("capital width", "m", "Z extent of the volutes (front to rear face)"),
    "spiral_margin": ("spiral margin length", "m", "straight band from a volute's top inward"),
    "scroll_position_y": (
        "vertical position of the scrolls",
        "m",
        "eye centre height above the capital bottom",
    ),
    "capital_position_y": (
        "vertical position of the capital",
        "m",
        "capital bottom above the shaft top",
    ),
    "abacus_length": ("", "m", "abacus X size"),
    "abacus_width": ("", "m", "abacus Z size"),
    "abacus_height": ("", "m", "abacus thickness"),
    "echinus_height": ("", "m", "height of the echinus (ovolo) cushion"),
    "echinus_projection": ("", "m", "how far the echinus reaches beyond the shaft top radius"),
    "relief_depth": ("", "m", "height of the band and eye above the channel floor"),
    "slab_depth": ("", "m", "thickness of the volute disc and canalis plate"),
    "spiral_samples": ("", "count", "samples along the spiral (LOD)"),
    "ring_segments": ("", "count", "segments around the echinus, bolsters and eyes (LOD)"),
    "bolster_rows": ("", "count", "rows along a bolster between front and rear (LOD)"),
}


#: The fields in metres (:meth:`CapitalParams.scaled`).
CAPITAL_LENGTHS = (
    "capital_length",
    "capital_width",
    "spiral_margin",
    "scroll_position_y",
    "capital_position_y",
    "abacus_length",
    "abacus_width",
    "abacus_height",
    "echinus_height",
    "echinus_projection",
    "relief_depth",
    "slab_depth",
)


@dataclass(frozen=True)
class CapitalParams:
    """Volute (Table 4), scroll grammar (Table 5), the five general parameters, abacus,
    echinus and level of detail. Defaults: Vitruvius for the Temple of Portunus (module
    docstring)."""

    volute: VoluteParams = field(default_factory=VoluteParams)
    scroll: str | ScrollGrammar = "S1"
    capital_length: float = 1.2656
    capital_width: float = _D
    spiral_margin: float = 0.4222
    scroll_position_y: float = 0.5 * _PART
    capital_position_y: float = 0.0
    abacus_length: float = _D * 19.0 / 18.0
    abacus_width: float = _D * 19.0 / 18.0
    abacus_height: float = 1.5 * _PART
    echinus_height: float = 2.5 * _PART
    echinus_projection: float = 1.5 * _PART
    relief_depth: float = 0.015
    slab_depth: float = 0.03
    spiral_samples: int = 192
    ring_segments: int = 48
    bolster_rows: int = 32
    _scroll: ScrollGrammar = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        ctx = "capital"
        if not isinstance(self.volute, VoluteParams):
            raise ParameterError("volute", self.volute, "a VoluteParams", context=ctx)
        if not isinstance(self.scroll, str | ScrollGrammar):
            raise ParameterError(
                "scroll", self.scroll, "a grammar string or preset name", context=ctx
            )
        object.__setattr__(self, "_scroll", resolve_scroll(self.scroll))
        check_fields(
            self,
            context=ctx,
            skip=("volute", "scroll"),
            integers={"spiral_samples": 8, "ring_segments": 3, "bolster_rows": 1},
            positive=(
                "capital_length",
                "capital_width",
                "abacus_length",
                "abacus_width",
                "abacus_height",
                "echinus_height",
                "relief_depth",
                "slab_depth",
            ),
            non_negative=("spiral_margin", "echinus_projection"),
        )
        depth = 2 * (self.relief_depth + self.slab_depth)
        if self.capital_width <= depth:
            raise ParameterError(
                "capital_width",
                self.capital_width,
                f"> 2 × (relief_depth + slab_depth) = {depth:.4g} m (room for the bolsters)",
                context=ctx,
            )
        ext = volute_extent(self.volute, self.spiral_samples, self.ring_segments)
        need = 2 * float(ext[1, 0] - ext[0, 0])
        if self.capital_length < need:
            raise ParameterError(
                "capital_length",
                self.capital_length,
                f">= {need:.4g} m: two volutes {need / 2:.4g} m wide must not overlap",
                context=ctx,
            )
        top = capital_height(self)
        if top <= 0:
            raise ParameterError(
                "capital_position_y",
                self.capital_position_y,
                f"a value that keeps the abacus top above the shaft top (it is at {top:.4g} m)",
                context=ctx,
            )

    @property
    def scroll_grammar(self) -> ScrollGrammar:
        """The parsed scroll rings."""
        return self._scroll

    def with_(self, **changes) -> CapitalParams:
        return replace(self, **changes)

    def scaled(self, factor: float) -> CapitalParams:
        """The same capital ``factor`` times as large (a column of ``factor`` times the lower
        diameter): every length scaled, the volute with it; sampling counts kept."""
        if isinstance(factor, bool) or not (isinstance(factor, int | float) and factor > 0):
            raise ParameterError("factor", factor, "a number > 0", context="capital")
        lengths = {n: getattr(self, n) * factor for n in CAPITAL_LENGTHS}
        return replace(self, volute=self.volute.scaled(factor), **lengths)


@dataclass(frozen=True)
class CapitalLayout:
    """Derived placements (m, capital frame before ``capital_position_y``)."""

    eye_x: float
    eye_y: float
    abacus_y: float
    face_z: float
    back_z: float
    total_radius: float
    #: length of each volute's straight margin (the band's run along the canalis' top)
    margin: float
    #: how far short of the centre plane x = 0 the margin stops (0: it reaches it)
    margin_gap: float


def capital_layout(p: CapitalParams) -> CapitalLayout:
    """Eye position, abacus bottom and the Z planes of the volute faces."""
    ext = volute_extent(p.volute, p.spiral_samples, p.ring_segments)
    eye_x = p.capital_length / 2 - float(ext[1, 0])
    eye_y = p.scroll_position_y
    abacus_y = max(eye_y + float(ext[1, 1]), p.echinus_height)
    face_z = p.capital_width / 2
    back_z = face_z - p.relief_depth - p.slab_depth
    # the band's top end lies on the eye's vertical line only for zero offsets: measure it
    top_end_x = eye_x + _top_end_dx(p.volute)
    margin = min(p.spiral_margin, max(0.0, top_end_x))
    return CapitalLayout(
        eye_x,
        eye_y,
        abacus_y,
        face_z,
        back_z,
        volute_total_radius(p.volute),
        margin,
        top_end_x - margin,
    )


def _top_end_dx(v: VoluteParams) -> float:
    """X of the band's top end relative to the eye centre."""
    return float(volute_curve(v, 2)[-1, 0]) - v.offset_x  # either volute model


def seat_depth(p: CapitalParams) -> float:
    """How far (m) a part resting on another's face is sunk into it: the band and eye into the
    volute's disc and the canalis, each bolster end into its disc, the canalis' top and the
    margin's far end up into the abacus (hidden: the abacus and its sizes are untouched).

    Faces that only touch are coincident planes for the union, and manifold3d may keep such a
    pair as a zero-thickness slit inside the solid (317 faces, 0.72 m², in the Portunus
    capital before this). 5 % of the thinner of relief and slab: 0.75 mm for Portunus, far
    below anything the eye or a scan resolves, and always inside the part it sinks into.
    """
    return 0.05 * min(p.relief_depth, p.slab_depth)


def capital_height(p: CapitalParams) -> float:
    """Top of the abacus above the shaft top (m): where the next element stacks."""
    ext = volute_extent(p.volute, p.spiral_samples, p.ring_segments)
    abacus_y = max(p.scroll_position_y + float(ext[1, 1]), p.echinus_height)
    return p.capital_position_y + abacus_y + p.abacus_height


def echinus_mesh(p: CapitalParams, top_radius: float, segments: int) -> Mesh:
    """The echinus: a convex quarter-ellipse ovolo from the shaft's top radius, revolved."""
    c, h, w = top_radius, p.echinus_height, p.echinus_projection
    n = max(4, segments // 4)
    phi = np.linspace(0.0, np.pi / 2, n + 1)
    # convex ovolo: quarter ellipse centred at (c, h), bulging outward and down
    arc = np.stack([c + w * np.sin(phi), h - h * np.cos(phi)], axis=1)
    if w == 0:
        arc = np.array([[c, 0.0], [c, h]])
    prof = np.vstack([[[0.0, 0.0]], arc, [[0.0, h]]])
    return lathe(prof, segments, "echinus")


def abacus_mesh(p: CapitalParams, lay: CapitalLayout) -> Mesh:
    """The abacus: a slab ``abacus_length`` × ``abacus_width`` on the volutes' top."""
    return box_mesh(
        (-p.abacus_length / 2, lay.abacus_y, -p.abacus_width / 2),
        (p.abacus_length / 2, lay.abacus_y + p.abacus_height, p.abacus_width / 2),
        "abacus",
    )


def canalis_bottom(p: CapitalParams, lay: CapitalLayout) -> float:
    """Bottom of the canalis plates: the echinus' top (not lower than the eyes), so the echinus
    runs under the canalis as a moulding (from the eye down it would cut the ovolo's top off
    flat)."""
    return min(max(lay.eye_y, p.echinus_height), lay.abacus_y - 1e-3)


def rim_radius(p: CapitalParams, lay: CapitalLayout) -> float:
    """The bolster's radius where it meets a volute (its first ring's: the scroll grammar's
    radius × the volute's total radius), about the eye's axis."""
    return float(p.scroll_grammar.rings[0].radius * lay.total_radius)


def bolster_profile(p: CapitalParams, length: float, radius: float) -> np.ndarray:
    """Bolster half-profile along its axis from the ring grammar.

    Rings at ``p·length`` with radius ``r·radius``; the first and last rings are held to p = 0
    and p = 1 (where the bolster meets the volute discs). Between rings the radius is a
    monotone cubic (PCHIP: smooth, no overshoot, so it never dips below the smaller
    neighbour); rings sharing a position make a flat step.

    Returns
    -------
    (n, 2) float: (radius, distance along the axis) from the axis at 0 to the axis at
    ``length``, the counter-clockwise order :func:`~ionic_usd.geometry.curves.revolve` wants.
    """
    rings = p.scroll_grammar.rings
    knots = [(r.position, r.radius) for r in rings]
    if knots[0][0] > 0:
        knots.insert(0, (0.0, knots[0][1]))
    if knots[-1][0] < 1:
        knots.append((1.0, knots[-1][1]))
    runs: list[list[tuple[float, float]]] = [[knots[0]]]
    for k in knots[1:]:
        if k[0] == runs[-1][-1][0]:
            runs.append([k])
        else:
            runs[-1].append(k)
    grid = np.linspace(0.0, 1.0, p.bolster_rows + 1)
    nodes: list[tuple[float, float]] = []
    for run in runs:
        ps = np.array([k[0] for k in run])
        rs = np.array([k[1] for k in run])
        if len(run) == 1:
            nodes.append((ps[0], rs[0]))
            continue
        inside = grid[(grid > ps[0]) & (grid < ps[-1])]
        t = np.union1d(ps, inside)
        nodes.extend(zip(t.tolist(), pchip(ps, rs, t).tolist(), strict=True))
    prof = [(0.0, 0.0)]
    for pos, r in nodes:
        node = (max(r, 0.0) * radius, pos * length)
        if node != prof[-1]:
            prof.append(node)
    prof.append((0.0, length))
    return np.asarray(prof)


@dataclass(frozen=True)
class CapitalParts:
    """The capital's meshes (capital frame, lifted by ``capital_position_y``).

    ``volutes``: front-right, front-left, rear-right, rear-left; ``canales``: front, rear;
    ``bolsters``: right, left; ``cores``: solid filling under the abacus (none in the normal
    capital). The angle capital's are listed in :func:`~ionic_usd.column.capital.build_capital`.
    """

    abacus: Mesh
    echinus: Mesh
    volutes: tuple[Mesh, ...]
    canales: tuple[Mesh, ...]
    bolsters: tuple[Mesh, ...]
    cores: tuple[Mesh, ...] = ()

    def as_dict(self) -> dict[str, Mesh]:
        """Name → mesh, in a stable order (names are valid USD prim names)."""
        out = {"abacus": self.abacus, "echinus": self.echinus}
        for m in (*self.volutes, *self.canales, *self.bolsters, *self.cores):
            out[m.name] = m
        return out

    def merged(self, name: str = "capital") -> Mesh:
        return merge(list(self.as_dict().values()), name=name)

    def lifted(self, dy: float) -> CapitalParts:
        """Every part moved up by ``dy`` (``capital_position_y``)."""
        if dy == 0:
            return self
        t = (0.0, float(dy), 0.0)

        def up(ms: tuple[Mesh, ...]) -> tuple[Mesh, ...]:
            return tuple(rigid(m, np.eye(3), t) for m in ms)

        return CapitalParts(
            rigid(self.abacus, np.eye(3), t),
            rigid(self.echinus, np.eye(3), t),
            up(self.volutes),
            up(self.canales),
            up(self.bolsters),
            up(self.cores),
        )


def bolster_mesh(
    p: CapitalParams,
    length: float,
    radius: float,
    *,
    extend: float = 0.0,
    lead: float = 0.0,
    name: str = "bolster",
) -> Mesh:
    """A bolster (pulvinus) on the −Z axis: the scroll grammar's rings from z = 0 (p = 0, the
    front volute's back) to z = −``length`` (p = 1), then, for ``extend`` > 0, a cylinder of the
    last ring's radius on to z = −(length + extend) (for a mitre cut, see the angle capital),
    and for ``lead`` > 0 one of the first ring's radius from z = ``lead`` (into the volute's
    disc, see :func:`seat_depth`).
    """
    prof = bolster_profile(p, length, radius)
    if extend > 0:
        prof = np.vstack([prof[:-1], [[prof[-2, 0], length + extend], [0.0, length + extend]]])
    if lead > 0:
        prof = np.vstack([[[0.0, -lead], [prof[1, 0], -lead]], prof[1:]])
    m = lathe(prof, p.ring_segments, name)
    # +Y (the lathe axis, p from 0 to 1) → −Z (front to rear)
    return rigid(m, np.array([[1.0, 0, 0], [0, 0, 1], [0, -1, 0]]), name=name)
