"""Shared fixtures."""

from __future__ import annotations

import atexit
import os
import shutil
import tempfile

import numpy as np
import pytest

# the UV/texture caches of a test run live in a fresh folder: tests see cold and warm builds
# of their own, never a developer's cache; removed when the run ends (each run fills ~2 GB)
_CACHE = tempfile.mkdtemp(prefix="ionic_usd_test_cache_")
os.environ["IONIC_USD_CACHE"] = _CACHE
atexit.register(shutil.rmtree, _CACHE, ignore_errors=True)


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(12345)


@pytest.fixture(scope="session")
def column_asset(tmp_path_factory):
    """The default column asset (small textures), built once per test session."""
    from ionic_usd.pipeline.asset import build_column_asset
    from ionic_usd.usd.column_asset import ColumnAssetOptions

    folder = tmp_path_factory.mktemp("asset") / "IonicColumn"
    report = build_column_asset(folder, ColumnAssetOptions(texture_size=64))
    return report


@pytest.fixture(scope="session")
def portunus_temple(tmp_path_factory):
    """The default Temple of Portunus scene (small textures), built once per test session."""
    from ionic_usd.pipeline.temple import compose_temple
    from ionic_usd.temple.layout import portunus_layout

    folder = tmp_path_factory.mktemp("temple") / "PortunusTemple"
    return compose_temple(folder, portunus_layout(), texture_size=64)


@pytest.fixture(scope="session")
def carved_temple(portunus_temple):
    """The default temple: its ``detail`` selection is ``carved`` (one build serves both)."""
    return portunus_temple


@pytest.fixture(scope="session")
def tiny_temple(tmp_path_factory):
    """The Portunus temple with a one-LOD column asset (low, one base, one scroll) and 16 px
    textures: every kind of composition the full temple has, in a few seconds."""
    from ionic_usd.pipeline.temple import compose_temple
    from ionic_usd.temple.layout import portunus_layout
    from ionic_usd.usd.column_asset import ColumnAssetOptions

    folder = tmp_path_factory.mktemp("tiny") / "TinyTemple"
    opts = ColumnAssetOptions(
        lods=("low",), bases=("attic_bezier_plinth",), scrolls=("S1",), texture_size=16
    )
    # detail = plain selected: the cuboid temple the export and reader tests count (the
    # detail variants are tested in test_detail.py)
    return compose_temple(
        folder, portunus_layout(), texture_size=16, asset_options=opts, detail="plain"
    )


@pytest.fixture(scope="session")
def tiny_city(tiny_temple):
    """A 2 x 2 city of the tiny temple (instanced temples + a PointInstancer of columns)."""
    import numpy as np

    from ionic_usd.blueprint.city import ColumnInstances, TempleInstances
    from ionic_usd.usd.city import compose_city

    city = tiny_temple.root.parent.parent
    name = tiny_temple.root.parent.name
    xz = np.array([[0.0, 0.0], [60.0, 0.0], [0.0, 60.0], [60.0, 60.0]])
    sel = [{}, {"roof-pitch-15": "alternative"}, {}, {"flutes-20": "alternative"}]
    temples = TempleInstances(
        [name], np.zeros(4, dtype=np.int32), ["a", "b", "c", "d"], xz, np.zeros(4), np.ones(4), sel
    )
    street = np.stack([np.arange(-27.0, 90.0, 3.0), np.full(39, 30.0)], axis=1)
    columns = ColumnInstances(f"{name}/IonicColumn/IonicColumn.usda", street, np.zeros(len(street)))
    return compose_city(city, temples, columns).path
