"""Static copies of small meshes baked into one glTF mesh per group (fewer draw calls).

A temple places 880 tegulae, 858 imbrices, 390 dentils and ~1,200 egg-and-dart and
bead-and-reel copies; one glTF node each costs a renderer one draw call each (three.js: 2,414
for the temple). :func:`plan_merges` groups the copies of every small mesh (at most
:data:`MERGE_MAX_TRIANGLES` triangles) by the point instancer that placed them (the path
before ``[i]``; copies placed otherwise — native instances such as the columns, which a user
selects one by one — stay one node each), and :func:`merged_streams`
bakes a group's copies into one vertex stream, relative to the group's first copy (the node's
transform), so two groups laid out alike (the same column prototype, a temple repeated in a
city) share one merged mesh. Every client draws the result: no extension is involved.

Transforms are row-vector (``p' = p @ M``): points ``p @ L + t``, normals ``n @ L⁻ᵀ``
(renormalised), tangents ``t @ L`` with ``w`` flipped and the triangles' winding reversed
where ``det L < 0``.
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass

import numpy as np

from ionic_usd.usd.reader import Placement, Scene

__all__ = [
    "MERGE_MAX_TRIANGLES",
    "MergeGroup",
    "group_of",
    "merged_streams",
    "plan_merges",
    "trs_decompose",
]

#: a mesh of at most this many triangles placed more than once is merged per group
MERGE_MAX_TRIANGLES = 2000


@dataclass(frozen=True)
class MergeGroup:
    """Copies of one scene mesh baked into one glTF mesh.

    ``frame`` (4, 4) is the node's matrix, ``relative`` (n, 4, 4) each copy's matrix relative
    to it (``placement.matrix = relative[i] @ frame``), ``key`` names the merged content (the
    mesh and the relative layout): equal keys share one glTF mesh.
    """

    mesh: str
    placements: tuple[Placement, ...]
    frame: np.ndarray
    relative: np.ndarray
    key: str


def group_of(p: Placement) -> str:
    """The point instancer that placed a copy (its path before ``[i]``), or ``""``."""
    i = p.path.find("[")
    return p.path[:i] if i >= 0 else ""


def trs_decompose(matrix: np.ndarray, tol: float = 1e-5):
    """Row-vector affine (4, 4) → ``(translation (3,), quaternion xyzw (4,), scale (3,))``.

    Returns None when the matrix has shear or a projective part (not a TRS).
    """
    from scipy.spatial.transform import Rotation  # noqa: PLC0415

    m = np.asarray(matrix, dtype=np.float64)
    if not np.allclose(m[:, 3], [0, 0, 0, 1], atol=1e-9):
        return None
    lin = m[:3, :3].T  # column-vector linear part: columns are the scaled axes
    scale = np.linalg.norm(lin, axis=0)
    if np.any(scale < 1e-12):
        return None
    rot = lin / scale
    if np.linalg.det(rot) < 0:
        scale[0], rot[:, 0] = -scale[0], -rot[:, 0]
    if not np.allclose(rot.T @ rot, np.eye(3), atol=tol):
        return None
    q = Rotation.from_matrix(rot).as_quat()
    q /= np.linalg.norm(q)
    return m[3, :3].copy(), q, scale


def _frame(m: np.ndarray) -> np.ndarray:
    """The group's node matrix: the first copy's, when glTF can store it (a TRS without
    shear), else only its translation."""
    if trs_decompose(m) is not None:
        return np.asarray(m, dtype=np.float64)
    f = np.eye(4)
    f[3, :3] = m[3, :3]
    return f


def plan_merges(
    scene: Scene, by_mesh: dict[str, list[Placement]], max_triangles: int = MERGE_MAX_TRIANGLES
) -> tuple[dict[str, list[Placement]], list[MergeGroup]]:
    """Split ``by_mesh`` (mesh key → its placements) into what stays one node per copy (or
    one GPU-instanced node) and the groups to merge."""
    keep: dict[str, list[Placement]] = {}
    groups: list[MergeGroup] = []
    for key, placements in by_mesh.items():
        if len(placements) < 2 or scene.meshes[key].n_triangles > max_triangles:
            keep[key] = placements
            continue
        by_group: dict[str, list[Placement]] = {}
        for p in placements:
            by_group.setdefault(group_of(p), []).append(p)
        for group, members in by_group.items():
            if not group or len(members) < 2:
                keep.setdefault(key, []).extend(members)
                continue
            frame = _frame(members[0].matrix)
            inv = np.linalg.inv(frame)
            rel = np.array([p.matrix for p in members]) @ inv
            h = hashlib.blake2b(key.encode(), digest_size=16)
            h.update((np.round(rel, 6) + 0.0).tobytes())  # + 0.0: -0.0 hashes as 0.0
            groups.append(MergeGroup(key, tuple(members), frame, rel, h.hexdigest()))
    return keep, groups


def merged_streams(streams, relative: np.ndarray):
    """One mesh's ``(pos, nrm, uv, tan, tris)`` (:func:`~ionic_usd.export.gltf_buffers.
    vertex_streams`) repeated at every matrix of ``relative`` (n, 4, 4), as one stream."""
    pos, nrm, uv, tan, tris = streams
    lin = relative[:, :3, :3]
    n, nv = len(relative), len(pos)
    p = np.einsum("vj,njk->nvk", pos.astype(np.float64), lin) + relative[:, None, 3, :3]
    inv_t = np.transpose(np.linalg.inv(lin), (0, 2, 1))
    q = np.einsum("vj,njk->nvk", nrm.astype(np.float64), inv_t)
    q /= np.linalg.norm(q, axis=2, keepdims=True)
    flip = np.linalg.det(lin) < 0
    out_uv = out_tan = None
    if uv is not None:
        out_uv = np.tile(uv, (n, 1))
        t = np.einsum("vj,njk->nvk", tan[:, :3].astype(np.float64), lin)
        t /= np.linalg.norm(t, axis=2, keepdims=True)
        w = np.where(flip[:, None], -tan[None, :, 3], tan[None, :, 3])
        out_tan = np.concatenate([t, w[:, :, None]], axis=2).reshape(-1, 4).astype(np.float32)
    tri = np.repeat(tris[None].astype(np.int64), n, axis=0)
    tri[flip] = tri[flip][:, :, ::-1]
    tri += (np.arange(n) * nv)[:, None, None]
    return (
        p.reshape(-1, 3).astype(np.float32),
        q.reshape(-1, 3).astype(np.float32),
        out_uv,
        out_tan,
        tri.reshape(-1, 3).astype(np.uint32),
    )
