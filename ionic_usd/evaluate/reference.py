"""Reference curves traced from drawings: CSV/SVG readers and alignment to generated curves.

A reference curve is an ``(n, 2)`` float array in metres (``scale`` converts from the file's
units). Readers raise :class:`~ionic_usd.errors.ReferenceCurveError` — and nothing else — for
any unreadable or malformed file; the message names the file and the line (CSV) or element
(SVG).

CSV format: one ``x,y`` point per line (``;``, tab or spaces also separate the two numbers);
blank lines and ``#`` comments (whole line or trailing) are ignored; the first data line may be
a header (any line with a non-numeric field).

SVG format: the first ``<path>`` element, or the element whose ``id`` is given (a ``<path>``
or any basic shape such as ``<polyline>``). Transforms are applied (svgelements ``reify``);
straight segments keep their end nodes, curved segments (Bézier, arcs) are sampled with
``samples_per_curve`` points each; resample the result with
:func:`ionic_usd.evaluate.metrics.resample` for constant spacing. SVG's y axis points down:
pass ``flip_y=True`` to get y up.
"""

from __future__ import annotations

import io
import math
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ionic_usd.errors import ParameterError, ReferenceCurveError
from ionic_usd.evaluate.metrics import hausdorff_distance
from ionic_usd.evaluate.polyline import PolylineIndex, as_curve, closest_on_polyline

__all__ = [
    "Alignment",
    "arc_centroid",
    "align",
    "read_csv_curve",
    "read_reference",
    "read_svg_curve",
]

_SPLIT = re.compile(r"[,;\s]+")


def _check_options(scale: float, samples_per_curve: int | None = None) -> None:
    if not (isinstance(scale, (int, float)) and math.isfinite(scale) and scale > 0):
        raise ParameterError("scale", scale, "a finite number > 0 (metres per file unit)")
    if samples_per_curve is not None and (
        not isinstance(samples_per_curve, int) or samples_per_curve < 2
    ):
        raise ParameterError("samples_per_curve", samples_per_curve, "an integer >= 2")


def _read_bytes(path: Path) -> bytes:
    try:
        return path.read_bytes()
    except OSError as exc:
        raise ReferenceCurveError(f"{path}: cannot read file: {exc.strerror or exc}") from exc


def _finish(points: np.ndarray, path: Path, where: str, scale: float, flip_y: bool) -> np.ndarray:
    if points.shape[0] == 0:
        raise ReferenceCurveError(f"{path}: {where}: no points")
    if points.shape[0] == 1:
        raise ReferenceCurveError(f"{path}: {where}: a single point is not a curve")
    if not np.all(np.isfinite(points)):
        raise ReferenceCurveError(f"{path}: {where}: non-finite coordinates")
    with np.errstate(over="ignore", invalid="ignore"):
        out = points * float(scale)
        seg = np.linalg.norm(np.diff(out, axis=0), axis=1)
    if flip_y:
        out[:, 1] = -out[:, 1]
    # Lengths must be finite too, or every measure downstream would be inf.
    if not (np.all(np.isfinite(out)) and np.all(np.isfinite(seg))):
        raise ReferenceCurveError(f"{path}: {where}: coordinates overflow (too large)")
    if not np.any(seg > 0.0):
        raise ReferenceCurveError(f"{path}: {where}: all points coincide (zero length)")
    return out


def read_csv_curve(path: str | Path, *, scale: float = 1.0, flip_y: bool = False) -> np.ndarray:
    """Read a polyline from a CSV/text file of ``x,y`` lines.

    Parameters
    ----------
    path : str or Path
    scale : float
        Metres per file unit.
    flip_y : bool
        Negate y (for curves traced in image coordinates).

    Returns
    -------
    (n, 2) float
        n >= 2, in metres.

    Raises
    ------
    ReferenceCurveError
        Unreadable or non-UTF-8 file, bad row, non-finite value, fewer than two points or a
        zero-length curve; the message names the file and line.
    """
    _check_options(scale)
    path = Path(path)
    data = _read_bytes(path)
    try:
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise ReferenceCurveError(
            f"{path}: not UTF-8 text (byte {exc.start}): {exc.reason}"
        ) from exc
    rows: list[tuple[float, float]] = []
    seen_content = False
    last_line = 0
    for lineno, raw in enumerate(text.split("\n"), start=1):
        line = raw.split("#", 1)[0].strip()
        if not line:
            continue
        fields = [f for f in _SPLIT.split(line) if f]
        try:
            values = [float(f) for f in fields]
        except ValueError:
            values = None
        if values is None:
            if not seen_content:  # a header line
                seen_content = True
                continue
            raise ReferenceCurveError(
                f"{path}: line {lineno}: bad row {line[:60]!r}: expected two numbers x,y"
            )
        seen_content = True
        if len(values) != 2:
            raise ReferenceCurveError(
                f"{path}: line {lineno}: bad row {line[:60]!r}: expected 2 values x,y, "
                f"got {len(values)}"
            )
        if not (math.isfinite(values[0]) and math.isfinite(values[1])):
            raise ReferenceCurveError(f"{path}: line {lineno}: non-finite value {line[:60]!r}")
        rows.append((values[0], values[1]))
        last_line = lineno
    if not rows:
        raise ReferenceCurveError(f"{path}: empty: no data rows")
    return _finish(np.array(rows, dtype=np.float64), path, f"line {last_line}", scale, flip_y)


def _element_name(element: object) -> str:
    tag = type(element).__name__.lower()
    ident = getattr(element, "id", None)
    return f"<{tag} id={ident!r}>" if ident else f"<{tag}>"


def read_svg_curve(
    path: str | Path,
    *,
    element_id: str | None = None,
    subpath: int | None = None,
    scale: float = 1.0,
    flip_y: bool = False,
    samples_per_curve: int = 64,
) -> np.ndarray:
    """Read a polyline from an SVG path (parsed and sampled with svgelements).

    Parameters
    ----------
    path : str or Path
    element_id : str, optional
        ``id`` of the element to read; default: the first ``<path>``.
    subpath : int, optional
        Which subpath (0-based, split at move-to commands) when the path has several; a path
        with several drawn subpaths and no ``subpath`` is an error.
    scale : float
        Metres per SVG user unit.
    flip_y : bool
        Negate y (SVG's y axis points down).
    samples_per_curve : int
        Points per curved segment (Bézier, arc), >= 2; straight segments keep their nodes.

    Returns the (n >= 2, 2) curve in metres, as :func:`read_csv_curve`; raises
    ReferenceCurveError for an unreadable or malformed file, no (matching) path, an empty
    path, ambiguous subpaths, a non-finite or degenerate curve, naming the file and element.
    """
    _check_options(scale, samples_per_curve)
    path = Path(path)
    data = _read_bytes(path)
    # svgelements is imported lazily: only SVG users need it.
    import svgelements as se

    try:
        svg = se.SVG.parse(io.BytesIO(data), reify=True)
        elements = list(svg.elements())
    except Exception as exc:  # noqa: BLE001 - any parser failure is a malformed file
        raise ReferenceCurveError(f"{path}: cannot parse SVG: {exc}") from exc

    chosen = None
    for element in elements:
        if element_id is not None:
            if getattr(element, "id", None) == element_id:
                chosen = element
                break
        elif isinstance(element, se.Path):
            chosen = element
            break
    if chosen is None:
        what = f"no element with id={element_id!r}" if element_id else "no <path> element"
        raise ReferenceCurveError(f"{path}: {what}")
    where = _element_name(chosen)
    try:
        points = _sample_svg_element(chosen, se, subpath, samples_per_curve, path, where)
    except ReferenceCurveError:
        raise
    except Exception as exc:  # noqa: BLE001 - malformed geometry inside svgelements
        raise ReferenceCurveError(f"{path}: {where}: cannot sample: {exc}") from exc
    return _finish(points, path, where, scale, flip_y)


def _sample_svg_element(element, se, subpath, samples, path, where) -> np.ndarray:
    if isinstance(element, se.Path):
        shape = element
    elif isinstance(element, se.Shape):
        shape = se.Path(element)
    else:
        raise ReferenceCurveError(f"{path}: {where} is not a path or shape")
    drawn = []
    for sub in shape.as_subpaths():
        segs = [s for s in sub if not isinstance(s, se.Move)]
        if segs:
            drawn.append(segs)
    if not drawn:
        raise ReferenceCurveError(f"{path}: {where}: empty path (no drawn segments)")
    if subpath is None:
        if len(drawn) > 1:
            raise ReferenceCurveError(
                f"{path}: {where}: {len(drawn)} subpaths; choose one with subpath=0.."
                f"{len(drawn) - 1}"
            )
        segs = drawn[0]
    else:
        if not 0 <= subpath < len(drawn):
            raise ReferenceCurveError(
                f"{path}: {where}: subpath {subpath} out of range 0..{len(drawn) - 1}"
            )
        segs = drawn[subpath]
    t = np.linspace(0.0, 1.0, samples)[1:]
    out: list[np.ndarray] = []
    for seg in segs:
        if seg.start is None or seg.end is None:
            continue
        if not out:
            out.append(np.array([[seg.start.x, seg.start.y]], dtype=np.float64))
        if isinstance(seg, (se.Line, se.Close)):
            out.append(np.array([[seg.end.x, seg.end.y]], dtype=np.float64))
        else:
            out.append(np.asarray(seg.npoint(t), dtype=np.float64).reshape(-1, 2))
    if not out:
        raise ReferenceCurveError(f"{path}: {where}: empty path (no drawn segments)")
    return np.concatenate(out)


def read_reference(
    path: str | Path,
    *,
    scale: float = 1.0,
    flip_y: bool = False,
    element_id: str | None = None,
    samples_per_curve: int = 64,
) -> np.ndarray:
    """Read a reference curve, choosing the reader by suffix (``.svg``; ``.csv``/``.txt``).

    Returns
    -------
    (n, 2) float
        In metres. See :func:`read_csv_curve` and :func:`read_svg_curve`.
    """
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix == ".svg":
        return read_svg_curve(
            path,
            element_id=element_id,
            scale=scale,
            flip_y=flip_y,
            samples_per_curve=samples_per_curve,
        )
    if suffix in (".csv", ".txt", ".tsv", ".dat"):
        return read_csv_curve(path, scale=scale, flip_y=flip_y)
    raise ReferenceCurveError(f"{path}: unknown reference format {suffix!r}; use .csv or .svg")


# --------------------------------------------------------------------------------------------
# alignment
# --------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Alignment:
    """What :func:`align` did to the generated curve, so reports can say so.

    The generated curve ``g`` becomes ``R(rotation) · M g + translation`` where ``M`` negates x
    when ``mirrored`` and ``R`` turns counter-clockwise by ``rotation`` degrees about the
    origin (2D only).

    Attributes
    ----------
    translation : tuple of float
        Added to the (possibly mirrored and rotated) generated curve, length d.
    mirrored : bool
        Whether x was negated (handedness flipped) first.
    hausdorff_before, hausdorff_after : float
        :func:`~ionic_usd.evaluate.metrics.hausdorff_distance` to the reference before and
        after; ``after <= before``.
    rotation : float
        Degrees, counter-clockwise, applied after the mirror (0 unless rotation was allowed).
    """

    translation: tuple[float, ...]
    mirrored: bool
    hausdorff_before: float
    hausdorff_after: float
    rotation: float = 0.0

    def __post_init__(self) -> None:
        if len(self.translation) not in (2, 3) or not all(
            math.isfinite(v) for v in self.translation
        ):
            raise ParameterError("translation", self.translation, "2 or 3 finite numbers")
        for name in ("hausdorff_before", "hausdorff_after"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0):
                raise ParameterError(name, value, "a finite number >= 0")
        if not math.isfinite(self.rotation) or (self.rotation and len(self.translation) != 2):
            raise ParameterError("rotation", self.rotation, "finite degrees, 2D curves only")

    def apply(self, curve: np.ndarray) -> np.ndarray:
        """The moved curve: mirror, rotate, translate.

        Parameters
        ----------
        curve : (n, d) float

        Returns
        -------
        (n, d) float
        """
        c = np.array(curve, dtype=np.float64)
        if self.mirrored:
            c[:, 0] = -c[:, 0]
        if self.rotation:
            a = math.radians(self.rotation)
            rot = np.array([[math.cos(a), -math.sin(a)], [math.sin(a), math.cos(a)]])
            c = c @ rot.T
        return c + np.asarray(self.translation)

    def describe(self) -> str:
        """One sentence for a report."""
        shift = ", ".join(f"{v:+.9g}" for v in self.translation)
        mirror = "mirrored in x, " if self.mirrored else ""
        turn = f"rotated {self.rotation:+.6g} deg, " if self.rotation else ""
        return (
            f"generated curve {mirror}{turn}translated by ({shift}) m; Hausdorff "
            f"{self.hausdorff_before:.6g} -> {self.hausdorff_after:.6g} m"
        )

    def as_dict(self) -> dict[str, object]:
        return {
            "translation": list(self.translation),
            "mirrored": self.mirrored,
            "rotation_deg": self.rotation,
            "hausdorff_before": self.hausdorff_before,
            "hausdorff_after": self.hausdorff_after,
        }


def arc_centroid(c: np.ndarray) -> np.ndarray:
    # Length-weighted centroid: independent of how densely the curve is sampled.
    seg = np.linalg.norm(np.diff(c, axis=0), axis=1)
    if c.shape[0] < 2 or seg.sum() == 0.0:
        return c.mean(axis=0)
    mid = 0.5 * (c[1:] + c[:-1])
    return (mid * seg[:, None]).sum(axis=0) / seg.sum()


def _rot(deg: float) -> np.ndarray:
    a = math.radians(deg)
    return np.array([[math.cos(a), -math.sin(a)], [math.sin(a), math.cos(a)]])


class _Brute:
    """Exact node-to-polyline distances by brute force (the index's interface)."""

    def __init__(self, poly: np.ndarray) -> None:
        self.poly = np.ascontiguousarray(poly, dtype=np.float64)

    def distances(self, points: np.ndarray) -> np.ndarray:
        return closest_on_polyline(np.ascontiguousarray(points, dtype=np.float64), self.poly)[0]


def _search(
    ref: np.ndarray,
    gen: np.ndarray,
    mirrored: bool,
    ang: float | None,
    before: float,
    start: np.ndarray | None = None,
    maxiter: int = 800,
) -> tuple[float, Alignment]:
    """Nelder–Mead on the Hausdorff distance over translation (and rotation if ``ang``)."""
    from scipy.optimize import minimize

    dim = ref.shape[1]
    g = gen.copy()
    if mirrored:
        g[:, 0] = -g[:, 0]
    ref_index: _Brute | PolylineIndex
    g_index: _Brute | PolylineIndex
    if len(ref) * len(g) <= 250_000:  # brute force (numba) beats the index on small curves
        ref_index, g_index = _Brute(ref), _Brute(g)
    else:
        ref_index, g_index = PolylineIndex(ref), PolylineIndex(g)
    cg, cr = arc_centroid(g), arc_centroid(ref)
    rotate = ang is not None

    def pose(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        # rotate about the generated centroid, then translate: g -> R (g - cg) + cg + t
        if rotate:
            rot = _rot(float(x[2]))
            return rot, cg - rot @ cg + x[:2]
        return np.eye(dim), np.asarray(x[:dim])

    def cost(x: np.ndarray) -> float:
        rot, t = pose(x)
        # d(ref node, R g + t) = d(R^T (ref node - t), g): both indexes are built once
        return float(
            max(ref_index.distances(g @ rot.T + t).max(), g_index.distances((ref - t) @ rot).max())
        )

    if start is not None:
        starts = [start]
    else:
        starts = [cr - cg] if mirrored else [cr - cg, np.zeros(dim)]
        if ang is not None:  # (= rotate)
            starts = [np.append(s, ang) for s in starts]
    x0 = min(starts, key=cost)
    f0 = cost(x0)
    span_r = float(np.linalg.norm(np.ptp(ref, axis=0))) or 1.0
    step = max(f0, 1e-9 * (1.0 + float(np.abs(ref).max())))
    steps = np.full(len(x0), step)
    if rotate:
        span = float(np.linalg.norm(np.ptp(g, axis=0))) or 1.0
        steps[2] = min(math.degrees(step / span) * 2.0, 20.0)
    simplex = np.vstack([x0, x0 + np.diag(steps)])
    res = minimize(
        cost,
        x0,
        method="Nelder-Mead",
        options={
            "initial_simplex": simplex,
            "xatol": 1e-7 * span_r,
            "fatol": 1e-9 * span_r,
            "maxiter": maxiter * len(x0),
        },
    )
    x, fx = (res.x, float(res.fun)) if res.fun <= f0 else (x0, f0)
    rot, t = pose(x)
    deg = 0.0
    if rotate:
        deg = float(x[2]) % 360.0
        deg = deg - 360.0 if deg > 180.0 else deg
    return fx, Alignment(tuple(float(v) for v in t), mirrored, before, max(fx, 0.0), deg)


def _refine(
    ref: np.ndarray, gen: np.ndarray, before: float, rough: Alignment
) -> tuple[np.ndarray, Alignment]:
    """Polish a coarse pose on the full curves (translation and rotation)."""
    g = gen.copy()
    if rough.mirrored:
        g[:, 0] = -g[:, 0]
    cg = arc_centroid(g)
    rot = _rot(rough.rotation)
    # translation t about the centroid that reproduces the rough pose: T = cg - R cg + t
    t = np.asarray(rough.translation) - (cg - rot @ cg)
    fx, how = _search(
        ref,
        gen,
        rough.mirrored,
        rough.rotation,
        before,
        start=np.append(t, rough.rotation),
        maxiter=300,
    )
    if fx >= before:
        how = Alignment(tuple(0.0 for _ in range(ref.shape[1])), False, before, before)
    aligned = how.apply(gen)
    after = hausdorff_distance(ref, aligned)
    return aligned, Alignment(
        how.translation, how.mirrored, before, min(after, before), how.rotation
    )


def align(
    reference: np.ndarray,
    generated: np.ndarray,
    *,
    allow_mirror: bool = False,
    allow_rotation: bool = False,
    rotation_starts: int = 8,
) -> tuple[np.ndarray, Alignment]:
    """Move the generated curve onto the reference (translation; optionally mirror, rotation).

    The centroids (arc-length weighted) are matched, then the pose is refined by minimising
    :func:`~ionic_usd.evaluate.metrics.hausdorff_distance` with Nelder–Mead (it is not
    differentiable). The untouched position is a candidate too, so the result is never worse
    than the input. With ``allow_mirror`` the generated curve with x negated is also tried and
    kept if it fits better (the handedness of a traced drawing is arbitrary). With
    ``allow_rotation`` (2D) the angle joins the search, started from ``rotation_starts`` angles
    evenly round the circle (the curves' own orientation is arbitrary in a scan or a drawing).

    Parameters
    ----------
    reference : (n, d) float
    generated : (m, d) float

    Returns
    -------
    aligned : (m, d) float
        The moved generated curve.
    alignment : Alignment
    """
    ref = as_curve(reference, "reference", min_nodes=2)
    gen = as_curve(generated, "generated", min_nodes=2)
    if ref.shape[1] != gen.shape[1]:
        raise ParameterError("generated", f"dimension {gen.shape[1]}", f"{ref.shape[1]}")
    if allow_rotation and ref.shape[1] != 2:
        raise ParameterError("allow_rotation", True, "2D curves only")
    before = hausdorff_distance(ref, gen)
    dim = ref.shape[1]
    if allow_rotation and min(len(ref), len(gen)) > 160:
        # coarse pose on 96-node copies from every start, then one refinement on the curves
        from ionic_usd.evaluate.metrics import resample

        r96, g96 = resample(ref, count=96), resample(gen, count=96)
        h96 = hausdorff_distance(r96, g96)
        rough: tuple[float, Alignment | None] = (h96, None)
        for mirrored in (False, True) if allow_mirror else (False,):
            for ang in np.arange(rotation_starts) * 360.0 / rotation_starts:
                fx, how = _search(r96, g96, mirrored, float(ang), h96, maxiter=40)
                if fx < rough[0]:
                    rough = (fx, how)
        if rough[1] is None:
            return _refine(ref, gen, before, Alignment((0.0, 0.0), False, before, before))
        return _refine(ref, gen, before, rough[1])
    best: tuple[float, Alignment | None] = (before, None)
    for mirrored in (False, True) if allow_mirror else (False,):
        angles = np.arange(rotation_starts) * 360.0 / rotation_starts if allow_rotation else [None]
        for ang in angles:
            fx, how = _search(ref, gen, mirrored, ang, before)
            if fx < best[0]:
                best = (fx, how)
    how = best[1] or Alignment(tuple(0.0 for _ in range(dim)), False, before, before)
    aligned = how.apply(gen)
    after = hausdorff_distance(ref, aligned)
    how = Alignment(how.translation, how.mirrored, before, min(after, before), how.rotation)
    return aligned, how
