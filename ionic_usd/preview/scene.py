"""The reader's scene as draw lists: one vertex buffer per distinct mesh, its placements, a colour.

No USD here: the input is :class:`ionic_usd.usd.reader.Scene` (numpy arrays and strings). A mesh
becomes per-corner positions and normals (fan triangles; flat normals where it has none), a
colour (its material's diffuse texture's mean or diffuse colour, else its display colour, else
stone grey), the local bound of its used points, and every placement's matrix. A card face
(a model drawn as cards) keeps its texture coordinates and image for the textured pass.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ionic_usd.geometry.mesh import face_normals, triangulate_fan
from ionic_usd.usd.reader import Scene, SceneMesh
from ionic_usd.usd.surface import MaterialData, TextureRef

__all__ = ["STONE_GREY", "DrawItem", "draw_items", "world_corners", "read_rgba"]

STONE_GREY = (0.50, 0.48, 0.44)  # linear RGB: a warm light limestone once lit


@dataclass
class DrawItem:
    """One mesh ready for upload, drawn once per placement.

    Attributes
    ----------
    key : the reader's mesh key
    vertices : (3 t, 6) float32 — per corner position, normal
    colour : linear RGB
    lo, hi : (3,) local bound of the mesh's used points
    placements : (n, 4, 4) float64 row-vector matrices (Y-up metres)
    instanced : how many placements came through native instancing or a PointInstancer
    uv : (3 t, 2) float32 texture coordinates of a card face, else None
    image : (h, w, 4) uint8 card image, bottom row first, else None
    """

    key: str
    vertices: np.ndarray
    colour: tuple[float, float, float]
    lo: np.ndarray
    hi: np.ndarray
    placements: np.ndarray
    instanced: int = 0
    uv: np.ndarray | None = None
    image: np.ndarray | None = None

    @property
    def triangles(self) -> int:
        return len(self.vertices) // 3


def read_rgba(path: str) -> np.ndarray | None:
    """An image as (h, w, 4) uint8 RGBA with its bottom row first (alpha 255 if it has none);
    None if unreadable."""
    import OpenImageIO as oiio  # noqa: PLC0415

    inp = oiio.ImageInput.open(path)
    if inp is None:
        return None
    try:
        spec = inp.spec()
        px = inp.read_image(0, 0, 0, min(spec.nchannels, 4), oiio.UINT8)
    finally:
        inp.close()
    if px is None:
        return None
    px = np.asarray(px, dtype=np.uint8)
    px = px[:, :, None] if px.ndim == 2 else px
    if px.shape[2] < 3:
        grey, alpha = px[:, :, :1], px[:, :, 1:2] if px.shape[2] == 2 else None
        px = np.concatenate(
            [np.repeat(grey, 3, axis=2)] + ([alpha] if alpha is not None else []), axis=2
        )
    if px.shape[2] == 3:
        px = np.concatenate([px, np.full(px.shape[:2] + (1,), 255, np.uint8)], axis=2)
    return np.ascontiguousarray(px[::-1])


def _mean_texture_colour(tex: TextureRef, cache: dict) -> np.ndarray | None:
    """The mean linear RGB of a texture (subsampled to about 512 rows) after its scale/bias."""
    from ionic_usd.texture.stone import srgb_to_linear  # noqa: PLC0415

    key = (tex.path, tex.colour_space)
    if key not in cache:
        import OpenImageIO as oiio  # noqa: PLC0415

        inp = oiio.ImageInput.open(tex.path)
        mean = None
        if inp is not None:
            try:
                spec = inp.spec()
                eight_bit = spec.format == oiio.TypeDesc(oiio.UINT8)
                px = inp.read_image(0, 0, 0, min(spec.nchannels, 3), oiio.FLOAT)
            finally:
                inp.close()
            if px is not None:
                px = np.asarray(px, dtype=np.float32)
                px = px[:, :, None] if px.ndim == 2 else px
                step = max(1, px.shape[0] // 512)
                px = px[::step, ::step]
                if px.shape[2] == 1:
                    px = np.repeat(px, 3, axis=2)
                space = tex.colour_space
                if space == "sRGB" or (space == "auto" and eight_bit):
                    px = srgb_to_linear(np.clip(px, 0.0, 1.0))
                mean = px.reshape(-1, px.shape[2])[:, :3].mean(axis=0).astype(np.float64)
        cache[key] = mean
    mean = cache[key]
    if mean is None:
        return None
    return np.clip(mean * np.asarray(tex.scale[:3]) + np.asarray(tex.bias[:3]), 0.0, None)


def _colour(mesh: SceneMesh, mat: MaterialData | None, cache: dict) -> tuple[float, float, float]:
    if mat is not None:
        if mat.diffuse_texture is not None:
            rgb = _mean_texture_colour(mat.diffuse_texture, cache)
            if rgb is not None:
                return tuple(float(x) for x in rgb)  # type: ignore[return-value]
        return tuple(float(x) for x in mat.diffuse)  # type: ignore[return-value]
    if mesh.display_color is not None:
        return mesh.display_color
    return STONE_GREY


def _corners(mesh: SceneMesh) -> tuple[np.ndarray, np.ndarray]:
    """Per-corner positions and normals of the fan triangles: two (3 t, 3) arrays."""
    idx = mesh.face_vertex_indices
    corners = triangulate_fan(mesh.face_vertex_counts, np.arange(len(idx))).astype(np.int64)
    tri_pts = mesh.points[idx[corners]]  # (t, 3, 3)
    nrm = mesh.normals
    if nrm is not None and mesh.normals_interpolation == "faceVarying":
        tri_nrm = nrm[corners]
    elif nrm is not None:
        tri_nrm = nrm[idx[corners]]
    else:  # flat shading from the winding
        fn, _ = face_normals(tri_pts.reshape(-1, 3), np.arange(3 * len(corners)).reshape(-1, 3))
        tri_nrm = np.repeat(fn[:, None, :], 3, axis=1)
    return tri_pts.reshape(-1, 3), np.asarray(tri_nrm).reshape(-1, 3)


def draw_items(scene: Scene) -> list[DrawItem]:
    """Every mesh of ``scene`` that has a placement, with its placements stacked."""
    by_mesh: dict[str, list] = {}
    for p in scene.placements:
        by_mesh.setdefault(p.mesh, []).append(p)
    colours: dict = {}
    images: dict[str, np.ndarray | None] = {}
    out = []
    for key, places in by_mesh.items():
        mesh = scene.meshes[key]
        mat = scene.materials.get(mesh.material) if mesh.material else None
        pos, nrm = _corners(mesh)
        verts = np.empty((len(pos), 6), dtype=np.float32)
        verts[:, :3], verts[:, 3:] = pos, nrm
        used = np.unique(mesh.face_vertex_indices)
        pts = mesh.points[used] if len(used) < len(mesh.points) else mesh.points
        item = DrawItem(
            key,
            verts,
            _colour(mesh, mat, colours),
            pts.min(axis=0),
            pts.max(axis=0),
            np.stack([p.matrix for p in places]),
            sum(p.via_instancing for p in places),
        )
        if mesh.card_face:
            tex = mat.diffuse_texture if mat is not None else None
            if tex is not None and tex.path not in images:
                images[tex.path] = read_rgba(tex.path)
            item.image = images.get(tex.path) if tex is not None else None
            idx = mesh.face_vertex_indices
            corners = triangulate_fan(mesh.face_vertex_counts, np.arange(len(idx)))
            item.uv = np.asarray(mesh.st, dtype=np.float32)[corners.reshape(-1)]
            if item.image is None:  # no image: the draw mode colour, opaque
                item.colour = mat.diffuse if mat else STONE_GREY
        out.append(item)
    return out


def world_corners(items: list[DrawItem]) -> np.ndarray:
    """(8 Σn, 3) world corners of every placed item's local bound."""
    out = []
    for d in items:
        box = np.array(
            [
                [x, y, z, 1.0]
                for x in (d.lo[0], d.hi[0])
                for y in (d.lo[1], d.hi[1])
                for z in (d.lo[2], d.hi[2])
            ]
        )
        out.append(np.einsum("ci,nij->ncj", box, d.placements)[..., :3].reshape(-1, 3))
    return np.concatenate(out)
