"""Reference curve readers (CSV, SVG), their errors, fuzzing, and alignment."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from numpy.testing import assert_allclose

from ionic_usd.errors import ParameterError, ReferenceCurveError
from ionic_usd.evaluate import metrics as M
from ionic_usd.evaluate.reference import (
    Alignment,
    align,
    read_csv_curve,
    read_reference,
    read_svg_curve,
)


def write(tmp_path: Path, name: str, content: str | bytes) -> Path:
    p = tmp_path / name
    if isinstance(content, bytes):
        p.write_bytes(content)
    else:
        p.write_text(content, encoding="utf-8")
    return p


# ------------------------------------------------------------------------------ CSV
def test_csv_header_comments_blank_lines_and_separators(tmp_path):
    p = write(
        tmp_path,
        "c.csv",
        "# traced from Piranesi\nx,y\n\n0,0\n1.5, 2  # trailing comment\n3;4\n5\t6\n7 8\n",
    )
    assert_allclose(read_csv_curve(p), [[0, 0], [1.5, 2], [3, 4], [5, 6], [7, 8]])


def test_csv_scale_and_flip(tmp_path):
    p = write(tmp_path, "c.csv", "0,0\n10,20\n")
    assert_allclose(read_csv_curve(p, scale=0.001, flip_y=True), [[0, 0], [0.01, -0.02]])


def test_csv_utf8_bom(tmp_path):
    p = write(tmp_path, "c.csv", "\ufeffx,y\n0,0\n1,1\n".encode())
    assert read_csv_curve(p).shape == (2, 2)


@pytest.mark.parametrize(
    ("content", "needle"),
    [
        ("", "empty"),
        ("# only a comment\n\n", "empty"),
        ("x,y\n", "empty"),
        ("x,y\n1,2\n", "single point"),
        ("0,0\n1,nan\n", "line 2: non-finite"),
        ("0,0\ninf,1\n", "line 2: non-finite"),
        ("0,0\n1,2,3\n", "line 2: bad row"),
        ("0,0\n1\n", "line 2: bad row"),
        ("x,y\n0,0\nfoo,bar\n", "line 3: bad row"),
        ("0,0\n0,0\n0,0\n", "zero length"),
        ("1e308,0\n-1e308,0\n", "overflow"),
    ],
)
def test_csv_errors_name_file_and_line(tmp_path, content, needle):
    p = write(tmp_path, "bad.csv", content)
    with pytest.raises(ReferenceCurveError) as info:
        read_csv_curve(p)
    assert str(p) in str(info.value)
    assert needle in str(info.value)


def test_csv_overflow_after_scaling(tmp_path):
    p = write(tmp_path, "c.csv", "1e308,0\n-1e308,0\n")
    with pytest.raises(ReferenceCurveError, match="overflow"):
        read_csv_curve(p, scale=10.0)


def test_unreadable_and_non_utf8(tmp_path):
    with pytest.raises(ReferenceCurveError, match="cannot read"):
        read_csv_curve(tmp_path / "missing.csv")
    with pytest.raises(ReferenceCurveError, match="cannot read"):
        read_svg_curve(tmp_path)  # a directory
    p = write(tmp_path, "latin.csv", b"x,y\n0,0\n\xff\xfe,1\n")
    with pytest.raises(ReferenceCurveError, match="not UTF-8"):
        read_csv_curve(p)


@pytest.mark.parametrize("scale", [0.0, -1.0, math.inf, math.nan])
def test_bad_scale(tmp_path, scale):
    p = write(tmp_path, "c.csv", "0,0\n1,1\n")
    with pytest.raises(ParameterError):
        read_csv_curve(p, scale=scale)


# ------------------------------------------------------------------------------ SVG
SVG_HEAD = '<svg xmlns="http://www.w3.org/2000/svg" width="100" height="100">'


def test_svg_first_path_lines_exact_and_transform(tmp_path):
    p = write(
        tmp_path,
        "a.svg",
        SVG_HEAD + '<g transform="translate(10,5)"><path d="M0 0 L10 0 L10 10"/></g>'
        '<path id="second" d="M0 0 L1 1"/></svg>',
    )
    assert_allclose(read_svg_curve(p), [[10, 5], [20, 5], [20, 15]])
    assert_allclose(read_svg_curve(p, element_id="second", scale=2.0), [[0, 0], [2, 2]])
    assert_allclose(read_reference(p, flip_y=True), [[10, -5], [20, -5], [20, -15]])


def test_svg_curved_segments_are_sampled_on_the_curve(tmp_path):
    # A semicircular arc of radius 5 centred at (5, 0): every sample is 5 from the centre.
    p = write(tmp_path, "arc.svg", SVG_HEAD + '<path d="M0 0 A5 5 0 0 1 10 0"/></svg>')
    pts = read_svg_curve(p, samples_per_curve=33)
    assert pts.shape == (33, 2)
    assert_allclose(np.linalg.norm(pts - [5.0, 0.0], axis=1), 5.0, atol=1e-9)
    # A quadratic Bézier: compare with the Bernstein form at the same parameters.
    q = write(tmp_path, "q.svg", SVG_HEAD + '<path d="M0 0 Q 5 10 10 0"/></svg>')
    t = np.linspace(0.0, 1.0, 9)
    ctrl = np.array([[0, 0], [5, 10], [10, 0]], dtype=float)
    bern = (
        ((1 - t) ** 2)[:, None] * ctrl[0]
        + (2 * t * (1 - t))[:, None] * ctrl[1]
        + (t**2)[:, None] * ctrl[2]
    )
    assert_allclose(read_svg_curve(q, samples_per_curve=9), bern, atol=1e-9)


def test_svg_shape_by_id_and_subpaths(tmp_path):
    p = write(
        tmp_path,
        "s.svg",
        SVG_HEAD + '<polyline id="pl" points="0,0 1,1 2,0"/>'
        '<path id="two" d="M0 0 L1 0 M5 5 L6 5 L7 5"/></svg>',
    )
    assert_allclose(read_svg_curve(p, element_id="pl"), [[0, 0], [1, 1], [2, 0]])
    with pytest.raises(ReferenceCurveError, match="2 subpaths"):
        read_svg_curve(p, element_id="two")
    assert_allclose(read_svg_curve(p, element_id="two", subpath=1), [[5, 5], [6, 5], [7, 5]])
    with pytest.raises(ReferenceCurveError, match="out of range"):
        read_svg_curve(p, element_id="two", subpath=2)


@pytest.mark.parametrize(
    ("body", "kwargs", "needle"),
    [
        ("<rect width='3' height='3'/>", {}, "no <path> element"),
        ("<path d='M0 0 L1 1'/>", {"element_id": "nope"}, "no element with id='nope'"),
        ("<path id='e' d=''/>", {}, "<path id='e'>: empty path"),
        ("<path id='m' d='M1 1'/>", {}, "empty path"),
        ("<path id='z' d='M1 1 L1 1'/>", {}, "zero length"),
        ("<path d='M0 0 L1e308 0 L-1e308 0'/>", {"scale": 10.0}, "overflow"),
    ],
)
def test_svg_errors_name_file_and_element(tmp_path, body, kwargs, needle):
    p = write(tmp_path, "bad.svg", SVG_HEAD + body + "</svg>")
    with pytest.raises(ReferenceCurveError) as info:
        read_svg_curve(p, **kwargs)
    assert str(p) in str(info.value)
    assert needle in str(info.value)


@pytest.mark.parametrize("content", [b"", b"not xml at all", b"<svg", b"\x00\xff<svg>"])
def test_svg_malformed(tmp_path, content):
    p = write(tmp_path, "m.svg", content)
    with pytest.raises(ReferenceCurveError, match=str(p).replace("\\", "\\\\")):
        read_svg_curve(p)


def test_unknown_suffix(tmp_path):
    with pytest.raises(ReferenceCurveError, match="unknown reference format"):
        read_reference(write(tmp_path, "c.json", "[]"))


# ------------------------------------------------------------------------------ fuzzing
FUZZ = settings(
    max_examples=150,
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture],
)

csv_like = st.lists(
    st.one_of(
        st.text(alphabet="0123456789.,;-+eE \t#xyinfa", max_size=20),
        st.floats(allow_nan=True, allow_infinity=True).map(repr),
        st.text(max_size=10),
    ),
    max_size=8,
).map("\n".join)

svg_like = st.one_of(
    st.binary(max_size=200),
    st.text(max_size=200).map(lambda s: SVG_HEAD + s + "</svg>"),
    st.text(alphabet="MLQCAZmlqcaz0123456789.,- eE", max_size=60).map(
        lambda d: SVG_HEAD + f'<path d="{d}"/></svg>'
    ),
    st.text(alphabet="<>/=\"' svgpathd0123456789MLA", max_size=120),
)


def _only_reference_errors(reader, path: Path) -> None:
    try:
        out = reader(path)
    except ReferenceCurveError:
        return
    assert out.ndim == 2 and out.shape[1] == 2 and out.shape[0] >= 2
    assert np.all(np.isfinite(out))


@FUZZ
@given(data=st.one_of(st.binary(max_size=200), csv_like.map(str.encode)))
def test_fuzz_csv_reader(tmp_path, data):
    p = tmp_path / "fuzz.csv"
    p.write_bytes(data)
    _only_reference_errors(read_csv_curve, p)


@FUZZ
@given(data=svg_like)
def test_fuzz_svg_reader(tmp_path, data):
    p = tmp_path / "fuzz.svg"
    p.write_bytes(data if isinstance(data, bytes) else data.encode("utf-8", "surrogatepass"))
    _only_reference_errors(read_svg_curve, p)


# ------------------------------------------------------------------------------ alignment
def profile(n: int = 200) -> np.ndarray:
    t = np.linspace(0.0, 1.0, n)
    return np.c_[0.3 + 0.05 * np.sin(6 * t) + 0.1 * t, t]  # asymmetric in x and y


def test_align_recovers_translation():
    ref = profile()
    shift = np.array([0.37, -0.12])
    aligned, info = align(ref, ref + shift)
    assert isinstance(info, Alignment)
    assert not info.mirrored
    assert_allclose(info.translation, -shift, atol=1e-6)
    assert_allclose(aligned, ref, atol=1e-6)
    assert info.hausdorff_after <= 1e-6 < info.hausdorff_before
    assert "translated" in info.describe()


def test_align_mirror_only_when_allowed():
    ref = profile()
    mirrored = ref * [-1.0, 1.0] + [0.05, 0.0]
    _, plain = align(ref, mirrored)
    aligned, info = align(ref, mirrored, allow_mirror=True)
    assert info.mirrored and not plain.mirrored
    assert info.hausdorff_after < 1e-6 < plain.hausdorff_after
    assert M.hausdorff_distance(ref, aligned) == pytest.approx(info.hausdorff_after)
    assert "mirrored" in info.describe()


def test_align_never_worse():
    rng = np.random.default_rng(5)
    ref = np.cumsum(rng.normal(size=(60, 2)), axis=0)
    gen = np.cumsum(rng.normal(size=(70, 2)), axis=0)
    aligned, info = align(ref, gen, allow_mirror=True)
    assert info.hausdorff_after <= info.hausdorff_before
    assert M.hausdorff_distance(ref, aligned) == pytest.approx(info.hausdorff_after)
    assert info.as_dict()["mirrored"] == info.mirrored
