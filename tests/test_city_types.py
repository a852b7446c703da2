"""City lots that name a preset or take a type fitted to them (ionic_usd.city.types)."""

from __future__ import annotations

import tomllib

import numpy as np
import pytest

from ionic_usd.city.choose import lot_rng, temple_for_lot
from ionic_usd.city.types import FILL, _footprint, choose_type, lot_size
from ionic_usd.pipeline.spec import temple_spec
from ionic_usd.temple.vitruvius import TempleType


def test_lot_size_of_a_rotated_rectangle():
    t = np.radians(30.0)
    r = np.array([[np.cos(t), -np.sin(t)], [np.sin(t), np.cos(t)]])
    ring = np.array([[0, 0], [20, 0], [20, 45], [0, 45.0]]) @ r.T + [100.0, 50.0]
    assert lot_size(ring) == pytest.approx((20.0, 45.0))


def test_choices_fit_their_lots_and_vary():
    rng = np.random.default_rng(11)
    slugs = set()
    for width, depth in ((30.0, 50.0), (52.0, 52.0), (18.0, 60.0)) * 5:
        slug, text = choose_type(width, depth, rng)
        slugs.add(slug)
        t = TempleType(**tomllib.loads(text)["type"])
        fw, fl = _footprint(t)
        assert fw <= FILL * width * 1.01 and fl <= FILL * depth * 1.01
        assert max(fw / (FILL * width), fl / (FILL * depth)) > 0.97  # and fills one of them
    assert len(slugs) >= 9  # a city of such lots holds many distinct builds


def _auto(seed: int, lot: str) -> str:
    got = temple_for_lot(
        {"temple": "auto"}, lot_rng(seed, lot), width=40.0, depth=60.0, module_range=(0.3, 3.0)
    )
    assert got.description is not None
    return got.description


def test_auto_is_seeded_per_lot():
    assert _auto(0, "3") == _auto(0, "3")
    kinds = {tomllib.loads(_auto(0, str(i)))["type"]["arrangement"] for i in range(12)}
    texts = {_auto(0, str(i)) for i in range(12)}
    assert len(texts) >= 8 and len(kinds) >= 3  # arrangements beyond the pseudoperipteral


def test_lot_names_a_preset_with_column_variety():
    base = temple_spec("priene", texture_size=64)
    assert base.layout().name == "Temple of Athena Polias, Priene"
    v = temple_spec("priene", {"lower_diameter": 1.2}, texture_size=64)
    lay = v.layout()
    assert lay.params.columns_lower_diameter == pytest.approx(1.2)
    assert v.key != base.key
    h = temple_spec("nike", {"height": 4.2}, texture_size=64).layout()
    assert h.params.columns_height == pytest.approx(4.2)
