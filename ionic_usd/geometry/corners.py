"""The :class:`CornerValues` value: one attribute's value at every face corner of a mesh.

A mesh carries its normals and texture coordinates as per-corner values, stored once per
distinct value with an index per corner (``indices``), or — a point attribute — one value per
point that every corner at the point shares (``indices is None``). That is all the kernel
knows; how an attribute is written (USD's ``normals`` attribute with vertex interpolation, an
indexed faceVarying primvar, de-duplicated or not) is chosen by the writers
(:mod:`ionic_usd.usd.mesh`, :mod:`ionic_usd.pipeline.mesh_cache`).

Every kernel operation handles both attributes through the same few methods: expand to one
value per corner (:meth:`CornerValues.at_corners`), take or reorder corners
(:meth:`~CornerValues.take`, :meth:`~CornerValues.reorder`), concatenate
(:func:`concat_corner_values`), map the values (:meth:`~CornerValues.with_values`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ionic_usd.errors import GeometryError

__all__ = ["CornerValues", "concat_corner_values"]


def _frozen(a: np.ndarray) -> np.ndarray:
    a = np.ascontiguousarray(a)
    a.setflags(write=False)
    return a


@dataclass(frozen=True, eq=False)
class CornerValues:
    """Per-corner values of one mesh attribute (normals, st).

    Parameters
    ----------
    values : (w, d) float32
        The values.
    indices : (k,) int32 or None
        Corner c (in ``face_vertex_indices`` order) has value ``values[indices[c]]``; None:
        the values are per point (``w`` = the mesh's points) and corner c has
        ``values[face_vertex_indices[c]]``, shared by every corner at the point.
    distinct : bool
        The producer's promise that the values are already indexed: every value is used by a
        corner and no two values of one chart (triangles joined through shared values) are
        equal, as a generator emits one value per seam-split chart vertex. A writer may then
        write them as they are instead of de-duplicating them (a sort of every value). Values
        of different charts may coincide (metric charts overlap until packed); they stay
        apart, which keeps the charts apart for a reader. A broken promise costs only a
        larger file: the expanded values are written exactly either way. Operations that
        replace values or indices drop it unless they keep the promise.
    """

    values: np.ndarray
    indices: np.ndarray | None = None
    distinct: bool = False
    # set by per_corner(): indices == arange(len(values)), so at_corners needs no gather
    _flat: bool = field(default=False, init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        v = np.asarray(self.values, dtype=np.float32)
        if v.ndim != 2:
            raise GeometryError(f"corner values of shape {v.shape}, expected (w, d)")
        object.__setattr__(self, "values", _frozen(v))
        if self.indices is not None:
            i = np.asarray(self.indices, dtype=np.int32).reshape(-1)
            if i.size and (i.min() < 0 or i.max() >= len(v)):
                raise GeometryError(f"corner value index outside 0..{len(v) - 1}")
            object.__setattr__(self, "indices", _frozen(i))
        object.__setattr__(self, "distinct", bool(self.distinct))

    @classmethod
    def per_corner(cls, values: np.ndarray, distinct: bool = False) -> CornerValues:
        """One value per corner, in corner order (``indices = arange``)."""
        out = cls(values, None, distinct)
        # in range by construction: no validation pass over them
        object.__setattr__(out, "indices", _frozen(np.arange(len(out.values), dtype=np.int32)))
        object.__setattr__(out, "_flat", True)
        return out

    @property
    def by_point(self) -> bool:
        """The values are per point, shared by every corner at a point."""
        return self.indices is None

    @property
    def one_per_corner(self) -> bool:
        """Known to hold one value per corner in corner order (made by :meth:`per_corner`):
        ``indices`` is ``arange(k)`` and :meth:`at_corners` is ``values`` itself."""
        return self._flat

    @property
    def dim(self) -> int:
        return int(self.values.shape[1])

    def corner_indices(self, face_vertex_indices: np.ndarray) -> np.ndarray:
        """(k,) index into ``values`` of every corner."""
        return face_vertex_indices if self.indices is None else self.indices

    def at_corners(self, face_vertex_indices: np.ndarray) -> np.ndarray:
        """(k, d) float32 value of every corner, in ``face_vertex_indices`` order."""
        if self._flat:
            return self.values
        return self.values[self.corner_indices(face_vertex_indices)]

    def take(self, corners: np.ndarray, face_vertex_indices: np.ndarray) -> CornerValues:
        """The values of the corners ``corners`` (indices into the k corners) as the corners
        of a new mesh; point values become per-corner (the points may change)."""
        if self.indices is None:
            return CornerValues.per_corner(self.values[face_vertex_indices[corners]])
        if self._flat:
            return CornerValues.per_corner(self.values[corners])
        return CornerValues(self.values, self.indices[corners])

    def reorder(self, perm: np.ndarray) -> CornerValues:
        """The corners permuted within their faces on the same points (``perm``: each new
        corner's old one): point values stay, the same values stay used (``distinct`` kept)."""
        if self.indices is None:
            return self
        if self._flat:
            return CornerValues.per_corner(self.values[perm], self.distinct)
        return CornerValues(self.values, self.indices[perm], self.distinct)

    def with_values(self, values: np.ndarray) -> CornerValues:
        """The same indexing with new values, one per old value (``distinct`` dropped)."""
        out = CornerValues(values, self.indices)
        object.__setattr__(out, "_flat", self._flat)
        return out

    def check(self, n_points: int, n_corners: int, what: str, name: str) -> None:
        """Raise GeometryError unless these fit a mesh of ``n_points`` and ``n_corners``."""
        if self.indices is None and len(self.values) != n_points:
            raise GeometryError(
                f"mesh {name!r}: {len(self.values)} {what} per point, expected {n_points}"
            )
        if self.indices is not None and self.indices.size != n_corners:
            raise GeometryError(
                f"mesh {name!r}: {self.indices.size} {what} indices for {n_corners} corners"
            )


def concat_corner_values(
    parts: list[CornerValues], face_vertex_indices: list[np.ndarray]
) -> CornerValues:
    """The corner values of concatenated meshes (their points and corners in order):
    per point if every part is; indexed if some part is indexed (each part indexing its own
    values, a per-point part through its face vertices); else one value per corner."""
    if all(p.indices is None for p in parts):
        return CornerValues(np.concatenate([p.values for p in parts]))
    if all(p.indices is None or p._flat for p in parts):
        corner = [p.at_corners(f) for p, f in zip(parts, face_vertex_indices, strict=True)]
        return CornerValues.per_corner(np.concatenate(corner))
    offsets = np.cumsum([0] + [len(p.values) for p in parts[:-1]])
    idx = [
        p.corner_indices(f) + o for p, f, o in zip(parts, face_vertex_indices, offsets, strict=True)
    ]
    return CornerValues(np.concatenate([p.values for p in parts]), np.concatenate(idx))
