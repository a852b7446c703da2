"""``ionic-usd web`` in a real browser (headless Chromium through playwright-core, run by
``tools/node/web_check.mjs``): toggles change the image only where they should, the panel
shows the USD's paradata, the permalink restores the view. Needs ``npm ci`` in tools/node and
Chromium (``tools/check_web.sh`` installs both; CI runs it)."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
from pathlib import Path

import pytest
from pxr import Usd

NODE_DIR = Path(__file__).resolve().parent.parent / "tools" / "node"
CHROMIUM = os.environ.get("CHROMIUM", "/usr/bin/chromium")

pytestmark = [
    pytest.mark.slow,
    pytest.mark.skipif(
        not (NODE_DIR / "node_modules" / "playwright-core").is_dir()
        or not Path(CHROMIUM).is_file()
        or shutil.which("node") is None,
        reason="needs node, `npm ci` in tools/node and Chromium (tools/check_web.sh)",
    ),
]


@pytest.fixture(scope="module")
def checked(tiny_temple, tmp_path_factory):
    from ionic_usd.web import write_site

    site = tmp_path_factory.mktemp("web") / "site"
    write_site(tiny_temple.root, site, three=NODE_DIR / "node_modules" / "three")
    proc = subprocess.run(
        ["node", str(NODE_DIR / "web_check.mjs"), str(site), "--width", "960", "--height", "600"],
        capture_output=True,
        text=True,
        timeout=1200,
    )
    line = next((x for x in proc.stdout.splitlines() if x.startswith("RESULT ")), None)
    assert proc.returncode == 0 and line, proc.stderr[-3000:]
    return json.loads(line[len("RESULT ") :]), site


def test_no_console_error_and_nothing_from_outside(checked):
    res, _ = checked
    assert res["errors"] == [] and res["outside"] == []


def test_each_toggle_changes_the_image_only_where_its_parts_are(checked):
    res, site = checked
    data = json.loads((site / "data.json").read_text())
    toggles = [h["id"] for h in data["hypotheses"] if h["glb"]]
    assert toggles and sorted(res["hypotheses"]) == sorted(toggles)
    for hid, r in res["hypotheses"].items():
        assert r["inside"] > 0, hid  # it draws something different ...
        assert r["outside"] == 0, hid  # ... only inside the box of what it draws or hides
        assert r["restored"], hid  # and off again is the baseline image, pixel for pixel


def test_reliability_view_recolours_and_returns(checked):
    res, _ = checked
    assert res["reliability"]["changed"] > 10_000 and res["reliability"]["restored"]


def _usd_record(stage, path: str) -> dict:
    prim = stage.GetPrimAtPath(path.split("[")[0])
    while prim and "paradata" not in prim.GetCustomData():
        prim = prim.GetParent()
    assert prim, path
    return dict(prim.GetCustomData()["paradata"])


def test_a_click_shows_the_paradata_of_the_usd(checked, tiny_temple):
    res, _ = checked
    stage = Usd.Stage.Open(str(tiny_temple.root))
    stage.GetDefaultPrim().GetVariantSets().GetVariantSet("lod").SetVariantSelection("low")
    shown = [c["shown"] for c in res["clicks"] if c["shown"].get("path")]
    assert len(shown) >= 3
    for f in shown:
        rec = _usd_record(stage, f["path"])
        assert f["unit"] == rec["unit"] and f["evidence"] == rec["evidence"], f
        assert f["certainty"] == rec["certainty"] and f["description"] == rec["description"]
        assert f["sources"].split("\n") == list(rec["sources"])


def test_permalink_restores_view_hypotheses_selection_and_image(checked):
    res, _ = checked
    p = res["permalink"]
    assert p["state"] == p["reopened"] and p["state"]["view"] == "reliability"
    assert p["state"]["sel"] == "/Temple/Podium/die" and p["same"]


def test_frame_times_are_reported(checked):
    res, _ = checked
    ft = res["frameTimes"]
    print("frame times (ms):", ft)
    assert 0 < ft["median"] <= ft["p95"] <= ft["max"] and ft["triangles"] > 0


def _glb_triangles(glb: Path) -> int:
    """Triangles a GLB draws: each mesh node's primitives times its GPU instances."""
    import struct

    raw = glb.read_bytes()
    doc = json.loads(raw[20 : 20 + struct.unpack("<I", raw[12:16])[0]])
    acc = doc["accessors"]
    total = 0
    for node in doc["nodes"]:
        if "mesh" not in node:
            continue
        gpu = node.get("extensions", {}).get("EXT_mesh_gpu_instancing")
        copies = acc[gpu["attributes"]["TRANSLATION"]]["count"] if gpu else 1
        for p in doc["meshes"][node["mesh"]]["primitives"]:
            total += copies * acc[p["indices"]]["count"] // 3
    return total


@pytest.fixture(scope="module")
def city_lod(tmp_path_factory):
    """A 3 x 3 Portunus city's site, its level of detail at the default view and with the
    camera on one temple (tools/node/web_lod.mjs)."""
    from ionic_usd.pipeline.city import CityOptions, build_city
    from ionic_usd.web import write_site

    out = tmp_path_factory.mktemp("webcity")
    opts = CityOptions(rows=3, cols=3, texture_size=64, seed=1, temple="portunus")
    build_city(out / "city", opts)
    site = out / "site"
    write_site(out / "city" / "City.usda", site, three=NODE_DIR / "node_modules" / "three")
    temple = json.loads((site / "data.json").read_text())["lodGroups"][4]  # the middle one
    proc = subprocess.run(
        ["node", str(NODE_DIR / "web_lod.mjs"), str(site), "--focus", temple],
        capture_output=True,
        text=True,
        timeout=1200,
    )
    line = next((x for x in proc.stdout.splitlines() if x.startswith("LOD ")), None)
    assert proc.returncode == 0 and line, proc.stderr[-3000:]
    return json.loads(line[len("LOD ") :]), site, temple


def test_city_default_view_draws_far_temples_at_their_far_level(city_lod):
    res, site, _ = city_lod
    assert res["errors"] == []
    home, scene = res["home"], _glb_triangles(site / "scene.glb")
    # the units account for every triangle of the scene, each temple one unit
    assert sum(g["full"] for g in home["groups"]) == scene
    temples = [g for g in home["groups"] if g["key"].startswith("/City/Temples/")]
    assert len(temples) == 9 and all(g["proxy"] < g["full"] / 20 for g in temples)
    # drawn: the far levels and at most the budget's worth in full, a fraction of the scene
    far = sum(g["proxy"] for g in home["groups"])
    assert home["triangles"] <= max(home["budget"], max(g["full"] for g in temples)) + far
    assert home["triangles"] < scene / 4


def test_city_camera_on_a_temple_draws_it_in_full_and_picks_it(city_lod):
    res, _, temple = city_lod
    on = res["focus"][temple]
    assert on["unit"]["level"] == 1 and on["unit"]["inView"]
    assert on["triangles"] >= on["unit"]["full"]  # all of its triangles: none culled or coarse
    assert on["picked"].startswith(temple + "/")  # a click on it reaches its part's record
    rel = on["reliability"]
    assert rel["changed"] > 10_000 and rel["restored"]  # both levels recoloured, and back
    street = on["street"]  # at eye height on its lot, facing it: in full too
    assert street["unit"]["level"] == 1 and street["triangles"] >= street["unit"]["full"] // 2
