"""Procedural stone textures: determinism, tiling, ranges, files, user textures."""

from __future__ import annotations

import dataclasses
import math
import struct
from pathlib import Path

import numpy as np
import OpenImageIO as oiio
import pytest
from numpy.testing import assert_allclose

from ionic_usd.errors import IonicError, ParameterError
from ionic_usd.texture.colour import encode_srgb_inplace
from ionic_usd.texture.stone import (
    STONE_STYLES,
    TRAVERTINE,
    StoneStyle,
    TextureError,
    copy_user_textures,
    generate_stone_maps,
    get_stone_style,
    height_to_normal,
    linear_to_srgb,
    srgb_to_linear,
    validate_user_texture,
    write_stone_textures,
)

STYLES = sorted(STONE_STYLES)
MAP_NAMES = ("base_color", "roughness", "normal", "height")


# ------------------------------------------------------------------------------- generation


@pytest.mark.parametrize("style", STYLES)
def test_deterministic_per_seed(style):
    a = generate_stone_maps(style, 64, seed=3)
    b = generate_stone_maps(style, 64, seed=3)
    c = generate_stone_maps(style, 64, seed=4)
    for name in MAP_NAMES:
        assert np.array_equal(getattr(a, name), getattr(b, name)), name
        assert not np.array_equal(getattr(a, name), getattr(c, name)), name


def _planes(m):
    return {
        "height": m.height,
        "roughness": m.roughness,
        **{f"base_color{c}": m.base_color[..., c] for c in range(3)},
        **{f"normal{c}": m.normal[..., c] for c in range(3)},
    }


@pytest.mark.parametrize("style", STYLES)
@pytest.mark.parametrize("size", [64, 256])
def test_tileable(style, size):
    m = generate_stone_maps(style, size, seed=1)
    for name, img in _planes(m).items():
        for axis in (0, 1):
            interior = np.abs(np.diff(img, axis=axis))
            wrap = np.abs(np.take(img, 0, axis=axis) - np.take(img, -1, axis=axis))
            # The seam must be an ordinary neighbour pair: no larger than the largest interior
            # step, and of the same typical size (a non-periodic field fails the mean test).
            assert wrap.max() <= interior.max() + 1e-6, (name, axis)
            assert wrap.mean() <= 2.0 * interior.mean() + 1e-6, (name, axis)


def test_tiling_test_detects_a_seam():
    """The criterion above is not vacuous: a non-periodic ramp plus noise fails it."""
    rng = np.random.default_rng(0)
    img = np.linspace(0, 1, 64)[None, :] + 0.005 * rng.standard_normal((64, 64))
    wrap = np.abs(img[:, 0] - img[:, -1])
    assert wrap.max() > np.abs(np.diff(img, axis=1)).max()


@pytest.mark.parametrize("style", STYLES)
def test_shapes_dtypes_ranges(style):
    st = get_stone_style(style)
    m = generate_stone_maps(style, 128, seed=2)
    assert m.size == 128 and m.style == st.name and m.seed == 2
    assert m.base_color.shape == (128, 128, 3) and m.normal.shape == (128, 128, 3)
    assert m.roughness.shape == (128, 128) and m.height.shape == (128, 128)
    for name in MAP_NAMES:
        a = getattr(m, name)
        assert a.dtype == np.float32, name
        assert np.isfinite(a).all() and a.min() >= 0.0 and a.max() <= 1.0, name
    lo, hi = st.roughness_range
    assert m.roughness.min() >= lo - 1e-6 and m.roughness.max() <= hi + 1e-6
    assert m.height.min() == 0.0 and m.height.max() == pytest.approx(1.0)


@pytest.mark.parametrize("style", STYLES)
def test_mean_colour_is_the_style_colour(style):
    st = get_stone_style(style)
    m = generate_stone_maps(style, 256, seed=5)
    mean_lin = srgb_to_linear(m.base_color).reshape(-1, 3).mean(axis=0)
    # Veins and pores pull the mean away; the stone must still read as its base colour.
    assert_allclose(linear_to_srgb(mean_lin), st.base_color, atol=0.08)


@pytest.mark.parametrize("style", STYLES)
def test_normals_are_unit_with_positive_z(style):
    m = generate_stone_maps(style, 128, seed=0)
    n = m.normal * 2.0 - 1.0
    assert_allclose(np.linalg.norm(n, axis=-1), 1.0, atol=1e-5)
    assert n[..., 2].min() > 0.0


def test_travertine_is_banded_horizontally():
    h = generate_stone_maps("travertine", 256, seed=0).height
    along = np.abs(np.diff(h, axis=1)).mean()  # along a row: within a layer
    across = np.abs(np.diff(h, axis=0)).mean()  # across layers
    assert across > 1.15 * along
    m = generate_stone_maps("marble", 256, seed=0).height
    assert_allclose(np.abs(np.diff(m, axis=1)).mean(), np.abs(np.diff(m, axis=0)).mean(), rtol=0.1)


def test_same_seed_same_stone_at_every_resolution():
    """Fourier coefficients do not depend on the size: a 512 map box-filtered to 256 is the
    256 map (up to the finest detail only the larger one has)."""
    a = generate_stone_maps("travertine", 256, seed=9)
    b = generate_stone_maps("travertine", 512, seed=9)
    other = generate_stone_maps("travertine", 256, seed=10)
    for name in ("roughness", "height"):
        x = getattr(a, name).ravel()
        y = getattr(b, name).reshape(256, 2, 256, 2).mean(axis=(1, 3)).ravel()
        assert np.corrcoef(x, y)[0, 1] > 0.85, name
        assert abs(np.corrcoef(getattr(other, name).ravel(), y)[0, 1]) < 0.2, name


# ------------------------------------------------------------------------------- normals


def test_height_to_normal_matches_hand_computed_sine():
    n, depth = 32, 0.01
    col = np.arange(n)
    h = np.tile(np.sin(2 * np.pi * col / n), (n, 1))
    # Periodic central difference of sin: N sin(2 pi / N) cos(2 pi c / N) per unit of u.
    slope = depth * n * np.sin(2 * np.pi / n) * np.cos(2 * np.pi * col / n)
    expected = np.stack([-slope, np.zeros(n), np.ones(n)], axis=-1)
    expected /= np.linalg.norm(expected, axis=-1, keepdims=True)
    got = height_to_normal(h, depth)
    for r in (0, 7, n - 1):
        assert_allclose(got[r], expected, atol=1e-6)


def test_height_to_normal_is_opengl_y_up():
    # Height grows towards the bottom of the image (increasing row): the slope faces the top
    # of the image, which is +v in OpenGL convention, so the normal has n_y > 0.
    h = np.tile(np.sin(np.linspace(0, np.pi, 64, endpoint=False))[:, None], (1, 64))
    nrm = height_to_normal(h, 0.01)
    assert (nrm[5:25, :, 1] > 0).all()  # rising part of the sine
    assert (nrm[40:60, :, 1] < 0).all()  # falling part
    assert_allclose(nrm[..., 0], 0.0, atol=1e-7)
    # Rightward rise (increasing column) tilts the normal to -x.
    assert (height_to_normal(h.T, 0.01)[:, 5:25, 0] < 0).all()


def test_height_to_normal_is_translation_equivariant():
    h = np.random.default_rng(1).random((32, 48)).astype(np.float32)
    a = height_to_normal(np.roll(h, (5, -7), axis=(0, 1)), 0.003)
    b = np.roll(height_to_normal(h, 0.003), (5, -7), axis=(0, 1))
    assert_allclose(a, b, atol=1e-7)


def test_flat_style_gives_flat_normals():
    flat = dataclasses.replace(TRAVERTINE, name="flat", normal_strength=0.0)
    m = generate_stone_maps(flat, 32, 0)
    assert_allclose(m.normal, np.broadcast_to([0.5, 0.5, 1.0], m.normal.shape), atol=1e-7)


def test_srgb_round_trip_and_anchors():
    x = np.linspace(0, 1, 101, dtype=np.float32)
    assert_allclose(linear_to_srgb(srgb_to_linear(x)), x, atol=2e-6)
    assert_allclose(srgb_to_linear(np.float32([0.5]))[0], 0.21404, atol=1e-4)


def test_srgb_encoding_follows_the_standard_to_float32_resolution():
    """The table encoder against IEC 61966-2-1 evaluated value by value with math.pow: three
    points in every cell of the table (its knot, a quarter and three quarters in), random
    values, the linear segment exact, the range clipped, NaN of either sign kept."""
    rng = np.random.default_rng(11)
    first = int(np.float32(2.0**-9).view(np.int32))
    one = int(np.float32(1.0).view(np.int32))
    cells = np.arange(first, one, 1 << 13, dtype=np.int32)
    grid = np.concatenate([cells, cells + (1 << 11), cells + 3 * (1 << 11)]).view(np.float32)
    x = np.concatenate(
        [rng.uniform(0.0, 1.0, 20000), 10.0 ** rng.uniform(-9.0, 0.0, 20000), [0.0, 1.0]]
    ).astype(np.float32)
    x = np.concatenate([x, grid])
    knee = 0.0031308
    x = x[np.abs(x.astype(np.float64) - knee) > 1e-9]  # the two segments differ by 7e-7 there
    want = np.array(
        [12.92 * v if v <= knee else 1.055 * math.pow(v, 1 / 2.4) - 0.055 for v in x.tolist()]
    )
    got = linear_to_srgb(x).astype(np.float64)
    assert np.max(np.abs(got - want) / np.maximum(want, 1e-30)) < 2e-7
    low = x <= knee
    assert np.array_equal(got[low], (x[low] * np.float32(12.92)).astype(np.float64))
    assert linear_to_srgb(np.float32([-1.0, 2.0])).tolist() == [0.0, 1.0]
    # x86 makes 0/0 a NaN with the sign bit set: its bits as int32 are negative
    nans = np.copysign(np.float32([np.nan, np.nan]), np.float32([1.0, -1.0]))
    assert np.signbit(nans[1]) and np.isnan(linear_to_srgb(nans)).all()
    # in place, any shape, the same values
    m = x[: 20000 // 3 * 3].reshape(-1, 3).copy()
    encode_srgb_inplace(m)
    assert np.array_equal(m.reshape(-1), linear_to_srgb(x[: len(m) * 3]))


# ----------------------------------------------------------------------------- validation


@pytest.mark.parametrize("size", [0, 8, 15, 17, 100, 1000, 16384, 2.5, 32.0, True, "64", None])
def test_bad_sizes(size):
    with pytest.raises(ParameterError, match="size"):
        generate_stone_maps("marble", size, 0)


@pytest.mark.parametrize("size", [16, 32, np.int64(64)])
def test_good_sizes(size):
    assert generate_stone_maps("marble", size, 0).base_color.shape == (int(size), int(size), 3)


@pytest.mark.parametrize("seed", [-1, 1.5, True, "3"])
def test_bad_seeds(seed):
    with pytest.raises(ParameterError, match="seed"):
        generate_stone_maps("marble", 16, seed)


def test_unknown_style_lists_valid():
    with pytest.raises(ParameterError) as info:
        get_stone_style("granite")
    for name in STONE_STYLES:
        assert name in str(info.value)
    with pytest.raises(ParameterError):
        generate_stone_maps("granite", 16, 0)
    assert get_stone_style(TRAVERTINE) is TRAVERTINE


@pytest.mark.parametrize(
    "change",
    [
        {"name": "Bad Name"},
        {"base_color": (1.2, 0.5, 0.5)},
        {"vein_color": (0.5, 0.5)},
        {"vein_strength": -0.1},
        {"pore_density": 0.7},
        {"roughness_range": (0.8, 0.2)},
        {"normal_strength": math.nan},
        {"banding": 2.0},
    ],
)
def test_style_validation(change):
    with pytest.raises(ParameterError):
        dataclasses.replace(TRAVERTINE, **change)


def test_style_is_frozen():
    with pytest.raises(dataclasses.FrozenInstanceError):
        TRAVERTINE.vein_strength = 1.0  # type: ignore[misc]
    assert isinstance(TRAVERTINE, StoneStyle)


# ---------------------------------------------------------------------------------- files


def _png_chunks(path: Path) -> list[str]:
    data = path.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    chunks, i = [], 8
    while i < len(data):
        (length,) = struct.unpack(">I", data[i : i + 4])
        chunks.append(data[i + 4 : i + 8].decode("ascii"))
        i += 12 + length
    return chunks


def _read(path: Path, miplevel: int = 0) -> tuple[oiio.ImageSpec, np.ndarray, str]:
    inp = oiio.ImageInput.open(str(path))
    assert inp is not None, oiio.geterror()
    try:
        assert inp.seek_subimage(0, miplevel)
        spec = inp.spec()
        return spec, inp.read_image(0, 0, 0, spec.nchannels, oiio.UINT8), inp.format_name()
    finally:
        inp.close()


def test_png_files_round_trip(tmp_path):
    out = write_stone_textures(tmp_path / "tex", "travertine", 32, 5)
    assert set(out) == {"basecolor", "roughness", "normal"}
    assert {p.name for p in out.values()} == {
        "travertine_basecolor.png",
        "travertine_roughness.png",
        "travertine_normal.png",
    }
    m = generate_stone_maps("travertine", 32, 5)
    expected = {"basecolor": m.base_color, "roughness": m.roughness, "normal": m.normal}
    for key, path in out.items():
        spec, pixels, fmt = _read(path)
        assert fmt == "png"
        assert (spec.width, spec.height) == (32, 32)
        assert spec.nchannels == (1 if key == "roughness" else 3)
        assert spec.format == oiio.UINT8
        want = np.round(expected[key] * 255).reshape(32, 32, -1)
        assert np.abs(pixels.astype(int) - want).max() <= 1, key
    # Colour is tagged sRGB; data maps carry no gamma/sRGB chunk a viewer would apply.
    assert "sRGB" in _png_chunks(out["basecolor"])
    for key in ("roughness", "normal"):
        assert not {"sRGB", "gAMA", "iCCP"} & set(_png_chunks(out[key])), key
    # Decoded 8-bit normals stay unit length within quantisation and point outwards.
    _, pix, _ = _read(out["normal"])
    n = pix.astype(np.float64) / 255.0 * 2.0 - 1.0
    assert_allclose(np.linalg.norm(n, axis=-1), 1.0, atol=0.01)
    assert n[..., 2].min() > 0


def test_written_pngs_are_checked_whole_without_decoding(tmp_path):
    """verify_image checks a PNG by its chunks' lengths and CRCs: every written map passes
    (and decodes), and every damage a failed write leaves is refused: those that lose pixels
    as OpenImageIO's decoder refuses (or misreads) them, and also a lost or followed IEND,
    which the decoder lets pass."""
    from ionic_usd.texture.files import TextureError, verify_image

    out = write_stone_textures(tmp_path / "tex", "travertine", 64, 5)
    data = out["normal"].read_bytes()
    for path in out.values():
        verify_image(path)
        assert _read(path)[1] is not None
    bad = tmp_path / "bad.png"
    flipped = bytearray(data)
    flipped[len(data) // 2] ^= 0x01
    damages = {
        "cut mid-file": data[: len(data) // 2],
        "cut in IEND": data[:-3],
        "cut after the signature": data[:8],
        "a byte changed": bytes(flipped),
        "bytes after IEND": data + b"\0" * 16,
        "zeros (a hole)": data[:100] + b"\0" * (len(data) - 100),
        "not a PNG": b"GIF89a" + data[6:],
    }
    for what, damaged in damages.items():
        bad.write_bytes(damaged)
        with pytest.raises(TextureError, match="is the disk full"):
            verify_image(bad)
        inp = oiio.ImageInput.open(str(bad))  # the decoder does not read it back either
        if inp is not None and "IEND" not in what:
            spec = inp.spec()
            pix = inp.read_image(0, 0, 0, spec.nchannels, oiio.UINT8)
            decoded = pix is not None and not inp.has_error
            inp.close()
            assert not decoded or not np.array_equal(pix, _read(out["normal"])[1]), what


def test_write_is_atomic_and_overwrites(tmp_path):
    first = write_stone_textures(tmp_path, "marble", 16, 0)
    before = first["basecolor"].read_bytes()
    second = write_stone_textures(tmp_path, "marble", 16, 1)
    assert first == second
    assert second["basecolor"].read_bytes() != before
    # No temporary files are left behind.
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(p.name for p in second.values())


def test_tx_files_are_mipmapped_and_unconverted(tmp_path):
    out = write_stone_textures(tmp_path, "travertine", 32, 5, make_tx=True)
    assert set(out) == {
        "basecolor",
        "roughness",
        "normal",
        "basecolor_tx",
        "roughness_tx",
        "normal_tx",
    }
    for key in ("basecolor", "roughness", "normal"):
        tx = out[f"{key}_tx"]
        assert tx.suffix == ".tx"
        spec, level0, fmt = _read(tx)
        assert fmt == "tiff" and spec.tile_width > 0
        assert spec.nchannels == (1 if key == "roughness" else 3)
        # 32 -> 16 -> 8 -> 4 -> 2 -> 1: six levels, each half the previous.
        for level in range(6):
            s, _, _ = _read(tx, level)
            assert (s.width, s.height) == (32 >> level, 32 >> level)
        inp = oiio.ImageInput.open(str(tx))
        assert not inp.seek_subimage(0, 6)
        inp.close()
        # Level 0 holds the PNG's texels unchanged: no colour conversion.
        _, png, _ = _read(out[key])
        assert np.array_equal(level0, png), key
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(p.name for p in out.values())


# -------------------------------------------------------------------------- user textures


def _write_image(path: Path, fmt: str | None = None, size: int = 8) -> Path:
    pixels = np.random.default_rng(0).integers(0, 256, (size, size, 3), dtype=np.uint8)
    buf = oiio.ImageBuf(pixels)
    assert buf.write(str(path), oiio.UINT8, fmt or ""), oiio.geterror()
    return path


@pytest.fixture
def textures(tmp_path):
    src = tmp_path / "src"
    src.mkdir()
    good_png = _write_image(src / "stone.png")
    good_jpg = _write_image(src / "stone_rough.jpg")
    tif = _write_image(src / "img.tif")
    fake_png = src / "fake.png"  # a TIFF named .png
    fake_png.write_bytes(tif.read_bytes())
    png_as_jpg = src / "mislabelled.jpg"  # a real PNG with a JPEG extension
    png_as_jpg.write_bytes(good_png.read_bytes())
    garbage = src / "garbage.png"
    garbage.write_bytes(b"\x00not an image" * 10)
    big = _write_image(src / "big.png", size=256)
    truncated = src / "truncated.png"
    truncated.write_bytes(big.read_bytes()[: big.stat().st_size // 2])
    return {
        "png": good_png,
        "jpg": good_jpg,
        "tif": tif,
        "fake_png": fake_png,
        "png_as_jpg": png_as_jpg,
        "garbage": garbage,
        "truncated": truncated,
        "missing": src / "missing.png",
        "folder": src,
    }


@pytest.mark.parametrize("key", ["png", "jpg"])
def test_valid_user_textures_accepted(textures, key):
    assert validate_user_texture(textures[key]) == textures[key].resolve()
    assert validate_user_texture(str(textures[key])) == textures[key].resolve()


@pytest.mark.parametrize(
    ("key", "problem"),
    [
        ("missing", "does not exist"),
        ("folder", "not a regular file"),
        ("garbage", "cannot read"),
        ("fake_png", "tiff"),
        ("tif", "tiff"),
        ("png_as_jpg", "extension"),
        ("truncated", "cannot be decoded"),
    ],
)
def test_invalid_user_textures_refused(textures, key, problem):
    with pytest.raises(TextureError, match=problem) as info:
        validate_user_texture(textures[key])
    err = info.value
    assert isinstance(err, IonicError) and err.path == textures[key]
    assert str(textures[key]) in str(err)


@pytest.mark.parametrize("bad", ["missing", "tif", "fake_png", "garbage", "png_as_jpg"])
def test_copy_validates_everything_first(textures, tmp_path, bad):
    dest = tmp_path / "out"
    with pytest.raises(TextureError):
        copy_user_textures({"basecolor": textures["png"], "normal": textures[bad]}, dest)
    assert not dest.exists() or not any(dest.iterdir())


def test_copy_user_textures(textures, tmp_path):
    dest = tmp_path / "out"
    copied = copy_user_textures({"basecolor": textures["png"], "roughness": textures["jpg"]}, dest)
    assert copied == {"basecolor": dest / "stone.png", "roughness": dest / "stone_rough.jpg"}
    for role, src in (("basecolor", textures["png"]), ("roughness", textures["jpg"])):
        assert copied[role].read_bytes() == src.read_bytes()
    assert sorted(p.name for p in dest.iterdir()) == ["stone.png", "stone_rough.jpg"]
    # Copying onto itself is a no-op, not a truncation.
    again = copy_user_textures({"basecolor": copied["basecolor"]}, dest)
    assert again["basecolor"].read_bytes() == textures["png"].read_bytes()


def test_copy_refuses_name_clash(textures, tmp_path):
    other = tmp_path / "elsewhere"
    other.mkdir()
    clash = _write_image(other / "stone.png")
    dest = tmp_path / "out"
    with pytest.raises(TextureError, match="clashes"):
        copy_user_textures({"basecolor": textures["png"], "normal": clash}, dest)
    assert not dest.exists()


def test_large_tile_with_frequencies_beyond_the_shared_block():
    """2048 px tiles draw the finest grain (> 512 cycles per tile) from a second stream; the
    result must still be deterministic, in range and seamless."""
    a = generate_stone_maps("stucco_painted", 2048, seed=4)
    assert np.array_equal(a.height, generate_stone_maps("stucco_painted", 2048, seed=4).height)
    for img in (a.height, a.roughness):
        assert img.min() >= 0.0 and img.max() <= 1.0
        for axis in (0, 1):
            interior = np.abs(np.diff(img, axis=axis)).max()
            wrap = np.abs(np.take(img, 0, axis=axis) - np.take(img, -1, axis=axis)).max()
            assert wrap <= interior


def test_the_stone_maps_cache_follows_the_code(tmp_path, monkeypatch):
    """The generated maps are cached by their options, the package's code and the libraries:
    after an edit of the generator a run makes new maps instead of reusing the old ones."""
    from ionic_usd.pipeline import asset, keys

    monkeypatch.setenv("IONIC_USD_CACHE", str(tmp_path / "cache"))
    first = asset._stone_store("travertine", 16, 7, False)
    assert asset._stone_store("travertine", 16, 7, False) == first  # reused
    monkeypatch.setattr(keys, "source_digest", lambda: "an edited generator")
    second = asset._stone_store("travertine", 16, 7, False)
    assert second != first and second.parent == first.parent
    assert sorted(p.name for p in second.iterdir()) == sorted(p.name for p in first.iterdir())
