"""Scans: reading point clouds and meshes, and sampling meshes into synthetic scans.

Readers (the optional extra ``scan``: ``pip install ionic_usd[scan]`` brings plyfile and
trimesh; they are imported only here, when a file of their kind is read):

* ``.ply`` — the ``vertex`` element's x, y, z (plyfile; binary or ASCII; faces ignored);
* ``.obj`` — the vertices (trimesh, ``process=False`` so none are merged or dropped);
* ``.xyz``, ``.csv``, ``.txt`` — the first three numbers of every line (comma, semicolon or
  whitespace separated; ``#`` comments and one header line allowed).

Every reader returns an ``(n, 3)`` float array in the file's units (``scale`` → metres) and
raises :class:`~ionic_usd.errors.ReferenceCurveError` naming the file for anything unreadable.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ionic_usd.errors import ParameterError, ReferenceCurveError

__all__ = ["SCAN_SUFFIXES", "read_scan", "sample_surface", "synthetic_scan"]

#: File suffixes :func:`read_scan` reads.
SCAN_SUFFIXES = (".ply", ".obj", ".xyz", ".csv", ".txt")

#: Most points a scan may hold (the fit subsamples; the deviation covers every point).
MAX_POINTS = 20_000_000


def _need(module: str):
    import importlib

    try:
        return importlib.import_module(module)
    except ImportError:
        raise ReferenceCurveError(
            f"reading this scan needs {module}: install the optional extra "
            f"`pip install ionic_usd[scan]`"
        ) from None


def _text_points(path: Path) -> np.ndarray:
    import re

    rows: list[list[float]] = []
    split = re.compile(r"[,;\s]+")
    with path.open("r", encoding="utf-8", errors="strict") as fh:
        for k, line in enumerate(fh, 1):
            line = line.split("#", 1)[0].strip()
            if not line:
                continue
            fields = [f for f in split.split(line) if f]
            try:
                vals = [float(f) for f in fields[:3]]
            except ValueError:
                if not rows and k <= 2:
                    continue  # a header line
                raise ReferenceCurveError(f"{path}:{k}: not three numbers: {line[:60]!r}") from None
            if len(vals) < 3:
                raise ReferenceCurveError(f"{path}:{k}: fewer than three numbers")
            rows.append(vals)
            if len(rows) > MAX_POINTS:
                raise ReferenceCurveError(f"{path}: more than {MAX_POINTS:,} points")
    return np.asarray(rows, dtype=np.float64).reshape(-1, 3)


def read_scan(path: str | Path, *, scale: float = 1.0) -> np.ndarray:
    """Points of a scan file.

    Parameters
    ----------
    path : .ply, .obj, .xyz, .csv or .txt
    scale : metres per file unit

    Returns
    -------
    (n, 3) float, metres, n >= 100, all finite
    """
    path = Path(path)
    if not (math.isfinite(scale) and scale > 0):
        raise ParameterError("scale", scale, "a number > 0 (metres per unit)")
    suffix = path.suffix.lower()
    if suffix not in SCAN_SUFFIXES:
        raise ReferenceCurveError(f"{path}: a scan must end in one of {', '.join(SCAN_SUFFIXES)}")
    if not path.is_file():
        raise ReferenceCurveError(f"{path}: no such file")
    try:
        if suffix == ".ply":
            plyfile = _need("plyfile")
            ply = plyfile.PlyData.read(str(path))
            v = ply["vertex"]
            pts = np.column_stack([np.asarray(v[c], dtype=np.float64) for c in "xyz"])
        elif suffix == ".obj":
            trimesh = _need("trimesh")
            mesh = trimesh.load(str(path), process=False, force="mesh")
            pts = np.asarray(mesh.vertices, dtype=np.float64)
        else:
            pts = _text_points(path)
    except ReferenceCurveError:
        raise
    except Exception as exc:  # plyfile's parse errors, trimesh's, numpy's: all one refusal
        if not isinstance(exc, _READ_ERRORS) and type(exc).__module__.split(".")[0] not in (
            "plyfile",
            "trimesh",
        ):
            raise
        raise ReferenceCurveError(f"{path}: cannot read the scan ({exc})") from None
    if pts.ndim != 2 or pts.shape[1] != 3 or len(pts) < 100:
        raise ReferenceCurveError(f"{path}: a scan needs at least 100 points (x, y, z)")
    if not np.all(np.isfinite(pts)):
        raise ReferenceCurveError(f"{path}: non-finite coordinates")
    check_scan_extent(pts * scale, str(path))
    return pts * scale


#: What a scan reader may raise for a bad file (besides plyfile's and trimesh's own errors).
_READ_ERRORS = (
    OSError,
    ValueError,
    KeyError,
    IndexError,
    TypeError,
    AttributeError,
    UnicodeDecodeError,
    EOFError,
)

#: Largest coordinate (m) a scan may hold: a point farther than the Earth's radius from the
#: origin is not a survey of a column (and squares of such numbers overflow float64 sums).
MAX_COORDINATE = 1.0e7

#: Smallest extent (m) of a scan along its second and third principal directions, relative
#: to its first: below this the points lie on a line or a plane, not on a column.
MIN_FLATNESS = 0.01


def check_scan_extent(pts: np.ndarray, where: str) -> None:
    """Refuse points no column could give: coordinates past :data:`MAX_COORDINATE`, all
    points (nearly) one point, or points on a line or a plane (:data:`MIN_FLATNESS`)."""
    big = float(np.max(np.abs(pts)))
    if not big <= MAX_COORDINATE:
        raise ReferenceCurveError(
            f"{where}: coordinates up to {big:.3g} m (after --scale); a scan must lie within "
            f"{MAX_COORDINATE:.0e} m of its origin"
        )
    c = pts - pts.mean(axis=0)
    size = float(np.max(np.ptp(c, axis=0)))
    if not size > 1e-4:
        raise ReferenceCurveError(
            f"{where}: the points span {size * 1000:.3g} mm; a scan of a column spans more "
            "than 0.1 mm"
        )
    step = max(1, len(c) // 200_000)
    sv = np.linalg.svd(c[::step] / size, compute_uv=False)
    if sv[2] < MIN_FLATNESS * sv[0]:
        what = "a line" if sv[1] < MIN_FLATNESS * sv[0] else "a plane"
        raise ReferenceCurveError(
            f"{where}: the points lie on {what} (principal spreads {sv[0]:.3g} : {sv[1]:.3g} : "
            f"{sv[2]:.3g}, the least below {MIN_FLATNESS:g} of the greatest): not a column"
        )


#: Metres per unit of the ``--units`` names.
UNITS = {"m": 1.0, "cm": 0.01, "mm": 0.001, "in": 0.0254, "ft": 0.3048}


def detect_units(pts: np.ndarray, where: str) -> tuple[float, str]:
    """Metres per unit of a scan, from its least principal extent (a column's diameter, also
    in a colonnade): up to 6 units → metres, from 200 → millimetres; between, inches and
    centimetres cannot be told apart and the scan is refused (``--units`` names them)."""
    c = pts - pts.mean(axis=0)
    step = max(1, len(c) // 200_000)
    _, _, vt = np.linalg.svd(c[::step], full_matrices=False)
    extent = float(np.ptp(c @ vt[2]))
    if extent <= 6.0:
        return 1.0, "m"
    if extent >= 200.0:
        return 0.001, "mm"
    raise ReferenceCurveError(
        f"{where}: the points span {extent:.4g} units across: neither metres nor millimetres; "
        "give --units (in, cm, ft)"
    )


def sample_surface(
    points: np.ndarray, triangles: np.ndarray, n: int, *, seed: int = 0
) -> tuple[np.ndarray, np.ndarray]:
    """Points spread evenly by area over a triangle mesh (a synthetic scan).

    Parameters
    ----------
    points : (v, 3) float
    triangles : (t, 3) int
    n : number of samples

    Returns
    -------
    samples : (n, 3) float
    triangle : (n,) int, the triangle each sample lies on
    """
    rng = np.random.default_rng(seed)
    p = np.asarray(points, dtype=np.float64)[np.asarray(triangles)]
    area = 0.5 * np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=1)
    tri = rng.choice(len(p), size=n, p=area / area.sum())
    u, v = rng.random(n), rng.random(n)
    flip = u + v > 1
    u[flip], v[flip] = 1 - u[flip], 1 - v[flip]
    q = p[tri]
    return q[:, 0] + u[:, None] * (q[:, 1] - q[:, 0]) + v[:, None] * (q[:, 2] - q[:, 0]), tri


def synthetic_scan(
    meshes: dict,
    n: int = 30_000,
    *,
    noise: float = 0.0005,
    missing_sector: tuple[float, float] | None = (40.0, 100.0),
    holes: int = 5,
    hole_radius: float = 0.1,
    y_range: tuple[float, float] | None = None,
    seed: int = 0,
    hidden: tuple[tuple[float, float], ...] = (),
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A scan-like point set of meshes in column coordinates (Y up), in a random pose.

    Area-uniform samples, a missing angular sector (degrees about +Y, from +X towards +Z),
    ``holes`` balls removed, Gaussian noise ``noise`` (m) per coordinate, then a random
    rotation and translation.

    Parameters
    ----------
    meshes : name → Mesh
    y_range : keep only points with y in this range (a fragment)
    hidden : (y, r) discs a scanner cannot see (joints between parts, the ground): samples
        within 1e-6 m of height y and radius below r are dropped

    Returns
    -------
    points : (m, 3) float, m <= n
    rotation : (3, 3) float, ``scan = column @ rotation.T + translation``
    translation : (3,) float
    """
    from scipy.spatial.transform import Rotation

    rng = np.random.default_rng(seed)
    allp, allt, off = [], [], 0
    for mesh in meshes.values():
        counts = np.asarray(mesh.face_vertex_counts)
        idx = np.asarray(mesh.face_vertex_indices)
        if not np.all(counts == 3):
            raise ParameterError("meshes", "polygons", "triangle meshes")
        allp.append(np.asarray(mesh.points, dtype=np.float64))
        allt.append(idx.reshape(-1, 3) + off)
        off += len(mesh.points)
    pts, _ = sample_surface(np.concatenate(allp), np.concatenate(allt), 3 * n, seed=seed)
    for yh, rh in hidden:
        pts = pts[~((np.abs(pts[:, 1] - yh) < 1e-6) & (np.hypot(pts[:, 0], pts[:, 2]) < rh))]
    if y_range is not None:
        pts = pts[(pts[:, 1] >= y_range[0]) & (pts[:, 1] <= y_range[1])]
    if missing_sector is not None:
        ang = np.degrees(np.arctan2(pts[:, 2], pts[:, 0])) % 360.0
        pts = pts[~((ang > missing_sector[0]) & (ang < missing_sector[1]))]
    for _ in range(holes):
        c = pts[rng.integers(len(pts))]
        pts = pts[np.linalg.norm(pts - c, axis=1) > hole_radius]
    pts = pts[rng.choice(len(pts), min(n, len(pts)), replace=False)]
    pts = pts + rng.normal(0.0, noise, pts.shape)
    rot = Rotation.random(random_state=seed).as_matrix()
    t = rng.normal(0.0, 3.0, 3)
    return pts @ rot.T + t, rot, t
