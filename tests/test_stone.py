"""Procedural stone textures: determinism, tiling, ranges, files, user textures."""

from __future__ import annotations

import numpy as np
import OpenImageIO as oiio
import pytest

from ionic_usd.errors import ParameterError
from ionic_usd.texture.stone import (
    STONE_STYLES,
    TextureError,
    copy_user_textures,
    generate_stone_maps,
    get_stone_style,
    validate_user_texture,
    write_stone_textures,
)


@pytest.mark.parametrize("style", sorted(STONE_STYLES))
def test_deterministic_per_seed(style):
    a = generate_stone_maps(style, 64, seed=3)
    b = generate_stone_maps(style, 64, seed=3)
    c = generate_stone_maps(style, 64, seed=4)
    assert np.array_equal(a.base_color, b.base_color) and np.array_equal(a.normal, b.normal)
    assert not np.array_equal(a.base_color, c.base_color)


@pytest.mark.parametrize("style", sorted(STONE_STYLES))
def test_tileable(style):
    m = generate_stone_maps(style, 128, seed=1)
    for img in (m.height, m.base_color[..., 0], m.roughness):
        interior = max(np.abs(np.diff(img, axis=0)).max(), np.abs(np.diff(img, axis=1)).max())
        wrap = max(np.abs(img[0] - img[-1]).max(), np.abs(img[:, 0] - img[:, -1]).max())
        assert wrap <= interior + 1e-6


def test_ranges_and_unit_normals():
    m = generate_stone_maps("travertine", 64, seed=0)
    for a in (m.base_color, m.roughness, m.normal):
        assert a.dtype == np.float32 and a.min() >= 0 and a.max() <= 1
    n = m.normal * 2 - 1
    assert np.allclose(np.linalg.norm(n, axis=-1), 1, atol=1e-4)
    assert n[..., 2].min() > 0


@pytest.mark.parametrize("size", [0, 15, 100, 16384, 2.5, True])
def test_bad_sizes(size):
    with pytest.raises(ParameterError):
        generate_stone_maps("marble", size, 0)


def test_unknown_style_lists_valid():
    with pytest.raises(ParameterError, match="travertine"):
        get_stone_style("granite")


def test_png_and_tx_files(tmp_path):
    out = write_stone_textures(tmp_path, "travertine", 32, 5, make_tx=True)
    assert set(out) == {"basecolor", "roughness", "normal", "basecolor_tx", "roughness_tx",
                        "normal_tx"}
    for key, path in out.items():
        inp = oiio.ImageInput.open(str(path))
        assert inp is not None, key
        spec = inp.spec()
        assert (spec.width, spec.height) == (32, 32)
        assert spec.nchannels == (1 if key.startswith("roughness") else 3)
        if key.endswith("_tx"):
            assert inp.seek_subimage(0, 5)  # 32 → 1 px: six mip levels
            assert inp.spec().width == 1
        inp.close()
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(p.name for p in out.values())


def test_user_textures_validated_before_copy(tmp_path):
    good = write_stone_textures(tmp_path / "src", "marble", 16, 0)
    tif = tmp_path / "img.tif"
    buf = oiio.ImageBuf(oiio.ImageSpec(8, 8, 3, oiio.UINT8))
    assert buf.write(str(tif))
    fake = tmp_path / "fake.png"
    fake.write_bytes(tif.read_bytes())  # a TIFF named .png
    garbage = tmp_path / "garbage.png"
    garbage.write_bytes(b"\x00" * 100)
    for bad in (tmp_path / "missing.png", tif, fake, garbage):
        with pytest.raises(TextureError):
            validate_user_texture(bad)
        with pytest.raises(TextureError):
            copy_user_textures({"basecolor": good["basecolor"], "normal": bad}, tmp_path / "o")
        assert not (tmp_path / "o").exists() or not any((tmp_path / "o").iterdir())
    copied = copy_user_textures({k: v for k, v in good.items()}, tmp_path / "dst")
    assert all(p.read_bytes() == good[k].read_bytes() for k, p in copied.items())
