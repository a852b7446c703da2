"""Mesh checks used by tests, validators and users: closedness, winding, volume, degeneracy."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ionic_usd.geometry.mesh import Mesh, face_normals, unique_rows

__all__ = ["MeshReport", "inspect_mesh", "signed_volume", "boundary_edges"]


@dataclass(frozen=True)
class MeshReport:
    """Topological and geometric facts about a triangle mesh.

    ``closed``: every undirected edge is used by exactly two faces (edge-manifold, no border).
    ``consistent``: every directed edge occurs once (neighbours traverse shared edges in
    opposite directions), so the winding is consistent.
    """

    n_points: int
    n_triangles: int
    boundary_edges: int
    nonmanifold_edges: int
    repeated_directed_edges: int
    degenerate_faces: int
    duplicate_faces: int
    unused_points: int
    signed_volume: float
    area: float

    @property
    def closed(self) -> bool:
        return self.boundary_edges == 0 and self.nonmanifold_edges == 0

    @property
    def consistent(self) -> bool:
        return self.repeated_directed_edges == 0

    @property
    def watertight(self) -> bool:
        """Closed, consistently wound, outward (positive volume), no bad faces."""
        return (
            self.closed
            and self.consistent
            and self.signed_volume > 0
            and self.degenerate_faces == 0
            and self.duplicate_faces == 0
        )


def _edges(tri: np.ndarray) -> np.ndarray:
    return np.concatenate([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]])


def signed_volume(mesh: Mesh) -> float:
    """Signed volume by the divergence theorem (positive when faces wind outward)."""
    p = mesh.points[mesh.triangles]
    # shift to the centroid to keep the sum well conditioned far from the origin
    c = mesh.points.mean(axis=0)
    p = p - c
    return float(np.einsum("ij,ij->i", p[:, 0], np.cross(p[:, 1], p[:, 2])).sum() / 6.0)


def boundary_edges(mesh: Mesh) -> np.ndarray:
    """(b, 2) int: undirected edges used by exactly one triangle."""
    e = np.sort(_edges(mesh.triangles), axis=1)
    u, c = unique_rows(e, return_counts=True)
    return u[c == 1]


def inspect_mesh(mesh: Mesh, *, area_eps: float | None = None) -> MeshReport:
    """Compute a :class:`MeshReport` for a (fan-triangulated) mesh.

    Parameters
    ----------
    area_eps : float, optional
        Triangles with an area at or below this are degenerate; default is
        ``1e-12 × (bounding-box diagonal)²``.
    """
    tri = mesh.triangles
    directed = _edges(tri)
    _, dcount = unique_rows(directed, return_counts=True)
    und = np.sort(directed, axis=1)
    _, ucount = unique_rows(und, return_counts=True)
    _, areas = face_normals(mesh.points, tri)
    diag = float(np.linalg.norm(np.ptp(mesh.points, axis=0))) if mesh.n_points else 0.0
    eps = area_eps if area_eps is not None else 1e-12 * diag * diag
    st = np.sort(tri, axis=1)
    _, fcount = unique_rows(st, return_counts=True)
    used = np.zeros(mesh.n_points, dtype=bool)
    used[tri.reshape(-1)] = True
    return MeshReport(
        n_points=mesh.n_points,
        n_triangles=len(tri),
        boundary_edges=int((ucount == 1).sum()),
        nonmanifold_edges=int((ucount > 2).sum()),
        repeated_directed_edges=int((dcount > 1).sum()),
        degenerate_faces=int((areas <= eps).sum()),
        duplicate_faces=int((fcount - 1)[fcount > 1].sum()),
        unused_points=int((~used).sum()),
        signed_volume=signed_volume(mesh),
        area=float(areas.sum()),
    )
