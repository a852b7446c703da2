"""Mouldings swept along the temple: podium base and crown, architrave fasciae, cornice, raking
cornice (the ``moulded`` level of detail; SPEC §4, issue 17).

Each section is a **base grammar** string (:mod:`ionic_usd.grammar.base`, version 2: Bézier
modules ``R<r> H<h> …``; version 1 tori also parse) read in the *member's own units*: ``h`` is
a fraction of the member's height and ``r`` its projection beyond the face in the same unit,
so a hypothesis that changes the architrave height rescales its fasciae. The sections live in
the temple description's ``[mouldings]`` table (``portunus.toml`` cites each one), with the
same values as :class:`MouldingParams`' defaults.

Members and where they are swept (frame of :mod:`ionic_usd.temple.layout`):

``architrave``      closed loop round the architrave's outer faces (``±xe``, ``±ze``); the
                    section reaches ``back`` = the upper diameter behind the face (the stone
                    beam itself), so it *replaces* the plain ``architrave`` cuboid.
``cornice``         closed loop round the frieze faces at the cornice's bottom, up to the
                    corona's top; behind the frieze face (``r ≤ 0``) it rises to the cornice's
                    full height, the floor of the pediments; replaces the plain ``cornice``
                    cuboid together with
``sima``            the crowning cyma recta on the flanks only (open paths along the long
                    sides, ending flush with the front and rear corona): the horizontal cornice
                    under a pediment has no sima, the raking cornice carries it (Vitruvius
                    III.5.12–13). Its ``r`` reaches ``cornice_projection_ratio``.
``raking_cornice``  open paths along the pediments' slopes (front and rear), under the roof
                    slabs' soffit, projecting from the tympanum face; Vitruvius IV.3.5/IV.2.5:
                    no dentils on the raking cornice.
``podium_base``     open path round the die and the cheek walls (not across the stairs), on
``podium_crown``    the footing and under the stylobate; added to the plain cuboids (a 45°
                    chamfer behind the face keeps its faces off the cuboids' faces).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, fields
from importlib import resources
from typing import Any

import numpy as np

from ionic_usd.errors import GrammarError, ParameterError
from ionic_usd.geometry.mesh import Mesh
from ionic_usd.geometry.sweep import sweep
from ionic_usd.params import load_toml
from ionic_usd.temple.layout import PORTUNUS_TOML, TempleLayout

__all__ = [
    "MouldingParams",
    "MouldedMember",
    "moulding_section",
    "mouldings_from_tables",
    "portunus_mouldings",
    "moulding_meshes",
    "cornice_levels",
    "REPLACED_CUBOIDS",
]

# cuboids of the plain layout that the moulded members replace (the others stay)
REPLACED_CUBOIDS = ("architrave", "cornice")

# Default sections: see portunus.toml [mouldings] for the sources of every number.
_ARCHITRAVE = (
    "R0 H0 R0 H0.2143, R0 H0 R0.03 H0, R0.03 H0 R0.03 H0.2857, R0.03 H0 R0.06 H0, "
    "R0.06 H0 R0.06 H0.3571, "
    "R0.06 H0 R0.06 H0.0714 R0.2029 H0.0714 R0.2029 H0.1429"
)
_CORNICE = (
    "R0 H0 R0.16 H0 R0.16 H0.16, R0.16 H0 R0.16 H0.255, R0.16 H0 R0.415 H0, "
    "R0.415 H0 R0.458 H0 R0.458 H0.043, R0.458 H0 R0.85 H0, R0.85 H0 R0.85 H0.255"
)
_SIMA = "R0 H0 R0.87 H0, R0.87 H0 R0.87 H0.15 R1.0 H0.137 R1.0 H0.287"
_RAKING = (
    "R0 H0 R0.85 H0, R0.85 H0 R0.85 H0.255, R0.85 H0 R0.87 H0, "
    "R0.87 H0 R0.87 H0.15 R1.0 H0.137 R1.0 H0.287"
)
_PODIUM_BASE = (
    "R0.45 H0 R0.45 H0.15, R0.45 H0 R0.52 H0.15 R0.3 H0.3, R0.3 H0 R0.22 H0, "
    "R0.22 H0 R0.22 H0.2 R0.05 H0.1 R0.05 H0.3, R0.05 H0 R0.05 H0.25"
)
_PODIUM_CROWN = (
    "R0 H0 R0 H0.15 R0.2 H0.15 R0.2 H0.3, R0.2 H0 R0.25 H0, "
    "R0.25 H0 R0.25 H0.4, R0.25 H0 R0.33 H0 R0.33 H0.3"
)

# the dentil course inside the cornice section (fractions of the cornice height): the band's
# face, the dentils' front (projection = height, Vitruvius III.5.11) and the course's bottom/top
_DENTIL_BAND = {"face": 0.16, "front": 0.415, "bottom": 0.16, "top": 0.415}


@dataclass(frozen=True)
class MouldingParams:
    """The moulding sections of a temple (grammar strings in member units, see the module
    docstring) and the metric sizes the layout does not give."""

    architrave: str = _ARCHITRAVE
    cornice: str = _CORNICE
    sima: str = _SIMA
    raking_cornice: str = _RAKING
    podium_base: str = _PODIUM_BASE
    podium_crown: str = _PODIUM_CROWN
    podium_base_height: float = 0.475
    podium_crown_height: float = 0.475
    podium_back: float = 0.15
    slices: int = 6

    def __post_init__(self) -> None:
        for f in fields(self):
            v = getattr(self, f.name)
            if f.type == "str" or isinstance(f.default, str):
                if not isinstance(v, str) or not v.strip():
                    raise ParameterError(f"mouldings.{f.name}", v, "a base grammar string")
                moulding_section(v, 1.0, name=f"mouldings.{f.name}")  # parse now: caret errors
            elif f.name == "slices":
                if isinstance(v, bool) or not isinstance(v, int) or not 1 <= v <= 32:
                    raise ParameterError("mouldings.slices", v, "an integer 1 … 32")
            elif (
                isinstance(v, bool)
                or not isinstance(v, int | float)
                or not math.isfinite(v)
                or v <= 0
            ):
                raise ParameterError(f"mouldings.{f.name}", v, "a length > 0 (m)")


def moulding_section(
    grammar: str, scale: float, *, slices: int = 6, name: str = "moulding"
) -> np.ndarray:
    """The outer curve of a moulding section in metres.

    Parameters
    ----------
    grammar : base grammar text (``r`` = projection, ``h`` = height, member units)
    scale : metres per member unit (the member's height)

    Returns
    -------
    (n, 2) float (projection u, height v) from the bottom to the top, collapsed flat runs
    """
    from ionic_usd.column.base import BaseParams, base_profile

    d = 1.0  # the grammar's r is added to a radius: any d > max|r| keeps the check happy
    try:
        p = BaseParams(
            grammar=grammar,
            shaft_radius=d * max(1.0, scale),
            segments=8,
            profile_slices=slices,
            scale=scale,
        )
    except ParameterError as exc:
        raise ParameterError(name, exc.value, exc.valid) from None
    except GrammarError as exc:  # name the moulding: "mouldings.cornice (base v2) error …"
        raise exc.with_grammar(f"{name} ({exc.grammar})") from None
    out = base_profile(p).copy()
    out[:, 0] -= d * max(1.0, scale)
    return out


def _close(
    curve: np.ndarray, back: float, *, chamfer: bool, top: float | None = None
) -> np.ndarray:
    """Close an outer curve into a section polygon reaching ``back`` behind the face (u < 0).

    ``chamfer``: the back corners are cut at 45° so that the section touches the face plane
    (u = 0) only along its bottom and top edges (no face coplanar with the cuboid behind).
    ``top``: the back part (u ≤ 0) rises to this height, above the curve's end.
    """
    h = float(curve[-1, 1])
    if top is not None and not chamfer and top > h:
        return _close(np.vstack([curve, [[0.0, h], [0.0, top]]]), back, chamfer=False)
    pts: list[tuple[float, float]] = []
    if chamfer:
        b = min(back, 0.45 * h)
        pts.append((-b, b))
        if curve[0, 0] > 0:
            pts.append((0.0, 0.0))
    else:
        pts.append((-back, 0.0))
    pts += [tuple(p) for p in curve]
    if chamfer:
        if curve[-1, 0] > 0:
            pts.append((0.0, h))
        pts.append((-b, h - b))
    else:
        pts.append((-back, h))
    out = [pts[0]]
    for p in pts[1:]:
        if abs(p[0] - out[-1][0]) > 1e-12 or abs(p[1] - out[-1][1]) > 1e-12:
            out.append(p)
    if abs(out[0][0] - out[-1][0]) <= 1e-12 and abs(out[0][1] - out[-1][1]) <= 1e-12:
        out.pop()
    return np.array(out, dtype=np.float64)


def mouldings_from_tables(data: Mapping[str, Any], *, context: str = "temple") -> MouldingParams:
    """:class:`MouldingParams` from a temple TOML's ``[mouldings]`` table (absent → defaults)."""
    table = data.get("mouldings", {})
    if not isinstance(table, Mapping):
        raise ParameterError("[mouldings]", table, "a table", context=context)
    known = {f.name for f in fields(MouldingParams)}
    for k in table:
        if k not in known:
            raise ParameterError(
                f"mouldings.{k}", table[k], f"one of {', '.join(sorted(known))}", context=context
            )
    try:
        return MouldingParams(**table)
    except ParameterError as exc:
        raise ParameterError(exc.name, exc.value, exc.valid, context=context) from None
    except GrammarError as exc:
        raise exc.with_grammar(f"{context}: {exc.grammar}") from None


def portunus_mouldings() -> MouldingParams:
    """The ``[mouldings]`` of the packaged ``portunus.toml``."""
    ref = resources.files("ionic_usd") / "data" / PORTUNUS_TOML
    with resources.as_file(ref) as p:
        return mouldings_from_tables(load_toml(p), context=str(p))


@dataclass(frozen=True)
class MouldedMember:
    """One swept member: its mesh and what it replaces."""

    name: str
    mesh: Mesh
    replaces: str | None = None


def cornice_levels(layout: TempleLayout) -> dict[str, float]:
    """Heights and faces the ornament placement shares with the mouldings (metres).

    Keys: ``y_architrave``, ``y_frieze``, ``y_cornice``, ``y_top`` (cornice top), ``xe``,
    ``ze`` (frieze faces), ``cornice`` (its height), ``projection``, ``dentil_face``,
    ``dentil_front``, ``dentil_bottom``, ``dentil_top`` (absolute y / offsets from the frieze
    face), ``half_top`` (upper column radius).
    """
    p = layout.params
    a, f, c = p.entablature_heights
    half_top = p.columns_lower_diameter * p.columns_upper_diameter_ratio / 2
    y = p.podium_height + p.columns_height
    out = {
        "y_architrave": y,
        "y_frieze": y + a,
        "y_cornice": y + a + f,
        "y_top": y + a + f + c,
        "xe": p.x_axis + half_top,
        "ze": p.z_front_axis + half_top,
        "cornice": c,
        "projection": c * p.entablature_cornice_projection_ratio,
        "half_top": half_top,
    }
    for k, v in _DENTIL_BAND.items():
        out[f"dentil_{k}"] = v * c if k in ("face", "front") else out["y_cornice"] + v * c
    return out


def _rect(x: float, z: float, y: float) -> np.ndarray:
    return np.array([[-x, y, -z], [x, y, -z], [x, y, z], [-x, y, z]], dtype=np.float64)


def _outward(path: np.ndarray, axis: np.ndarray, inside: np.ndarray | None = None) -> np.ndarray:
    """Orient an open path so that ``cross(tangent, axis)`` of its first segment points away
    from ``inside`` (default: the path's centroid) — the side the moulding projects to."""
    side = np.cross(path[1] - path[0], axis)
    mid = 0.5 * (path[0] + path[1])
    ref = path.mean(axis=0) if inside is None else inside
    return path if np.dot(side, mid - ref) > 0 else path[::-1].copy()


def moulding_meshes(
    layout: TempleLayout, mp: MouldingParams | None = None, *, uv_scale: float = 0.5
) -> list[MouldedMember]:
    """The swept members of a layout (closed, outward meshes; see the module docstring)."""
    mp = mp or MouldingParams()
    out: list[MouldedMember] = []

    def member(name, grammar, scale, path, **kw) -> None:
        out.append(_member(mp, uv_scale, name, grammar, scale, path, **kw))

    lv = cornice_levels(layout)
    _entablature_members(layout, mp, lv, member)
    _podium_members(layout, mp, member)
    _raking_members(layout, mp, lv, member)
    return out


_UP = np.array([0.0, 1.0, 0.0])


def _member(
    mp: MouldingParams,
    uv_scale: float,
    name,
    grammar,
    scale,
    path,
    *,
    closed,
    chamfer,
    back,
    axis=_UP,
    swap=False,
    replaces=None,
    top=None,
    key=None,
    inside=None,
) -> MouldedMember:
    """One member: ``grammar``'s section at ``scale``, closed behind (``back``), swept along
    ``path`` (a ring when ``closed``; else turned to project away from ``inside``)."""
    curve = moulding_section(grammar, scale, slices=mp.slices, name=f"mouldings.{key or name}")
    sec = _close(curve, back, chamfer=chamfer, top=top)
    if swap:  # raking: the section's height runs along the slope normal, downward
        sec = np.stack([sec[:, 1] - curve[-1, 1], sec[:, 0]], axis=1)
    if not closed:
        path = _outward(path, np.asarray(axis, dtype=np.float64), inside)
    m = sweep(sec, path, axis=axis, closed=closed, uv_scale=uv_scale, name=name)
    return MouldedMember(name, m, replaces)


def _entablature_members(layout: TempleLayout, mp: MouldingParams, lv: dict, member) -> None:
    """Architrave and cornice: closed rings round the entablature, replacing the plain
    cuboids; and the sima along both long sides, on the cornice."""
    p = layout.params
    a, _, c = p.entablature_heights
    back = 2 * lv["half_top"]
    for name, grammar, scale, top in (
        ("architrave", mp.architrave, a, None),
        ("cornice", mp.cornice, c, c),
    ):
        ring = _rect(lv["xe"], lv["ze"], lv[f"y_{name}"])
        member(
            name,
            grammar,
            scale,
            ring,
            closed=True,
            chamfer=False,
            back=back,
            replaces=name,
            top=top,
        )
    y_sima = lv["y_cornice"] + float(moulding_section(mp.cornice, c)[-1, 1])
    zc = lv["ze"] + lv["projection"]
    for name, sgn in (("sima_left", -1.0), ("sima_right", 1.0)):
        x = sgn * lv["xe"]
        path = np.array([[x, y_sima, -zc], [x, y_sima, zc]])
        if abs(y_sima + float(moulding_section(mp.sima, c)[-1, 1]) - lv["y_top"]) > 1e-6 * c:
            raise ParameterError(
                "mouldings.sima",
                mp.sima,
                "heights that, added to the cornice's, make the cornice height",
                context=p.name,
            )
        member(
            name,
            mp.sima,
            c,
            path,
            closed=False,
            chamfer=False,
            back=0.0,
            key="sima",
            inside=np.array([0.0, y_sima, 0.0]),
        )


def _podium_members(layout: TempleLayout, mp: MouldingParams, member) -> None:
    """The podium's base and crown: round the die and the cheek walls, stopping at the
    stairs (none on a Greek crepidoma: steps, no moulded podium; temple.typed_layout)."""
    p = layout.params
    w2, l2, cw = p.stylobate_width / 2, p.stylobate_length / 2, p.podium_cheek_wall_width
    front = l2 + p.stair_run
    for name, grammar, hgt, y0 in (
        ("podium_base", mp.podium_base, mp.podium_base_height, p.podium_footing_height),
        (
            "podium_crown",
            mp.podium_crown,
            mp.podium_crown_height,
            p.podium_height - mp.podium_crown_height,
        ),
    ):
        if not getattr(p, "podium_mouldings", True):
            break
        if y0 < p.podium_footing_height - 1e-9 or y0 + hgt > p.podium_height + 1e-9:
            raise ParameterError(
                f"mouldings.{name}_height",
                hgt,
                "a height that fits on the podium's die",
                context=p.name,
            )
        u = np.array(
            [
                [-(w2 - cw), y0, front],
                [-w2, y0, front],
                [-w2, y0, -l2],
                [w2, y0, -l2],
                [w2, y0, front],
                [w2 - cw, y0, front],
            ]
        )
        member(name, grammar, hgt, u, closed=False, chamfer=True, back=mp.podium_back)


def _raking_members(layout: TempleLayout, mp: MouldingParams, lv: dict, member) -> None:
    """Raking cornices under the roof slabs' soffit line, on both pediments."""
    p = layout.params
    c = p.entablature_heights[2]
    back = 2 * lv["half_top"]
    tan = 2.0 / p.roof_tympanum_ratio
    xc = lv["xe"] + lv["projection"]
    ridge = xc * tan
    for name, sgn in (("raking_cornice_front", 1.0), ("raking_cornice_rear", -1.0)):
        z = sgn * lv["ze"]
        path = np.array(
            [[-xc, lv["y_top"], z], [0.0, lv["y_top"] + ridge, z], [xc, lv["y_top"], z]]
        )
        member(
            name,
            mp.raking_cornice,
            c,
            path,
            closed=False,
            chamfer=False,
            back=min(back, lv["ze"]),
            axis=(0.0, 0.0, sgn),
            swap=True,
        )
