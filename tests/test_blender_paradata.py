"""Blender (bpy 5.0.1, its own venv) shows every part's evidence class, certainty and sources
as custom properties when it imports the default temple (``userProperties:em:*``).

Needs ``IONIC_USD_BPY_PYTHON`` = the python of a venv with ``bpy==5.0.1`` (CI sets it).
"""

from __future__ import annotations

import json
import os
import subprocess

import pytest
from pxr import Usd, UsdGeom

BPY = os.environ.get("IONIC_USD_BPY_PYTHON")

pytestmark = [
    pytest.mark.slow,
    pytest.mark.skipif(not BPY, reason="IONIC_USD_BPY_PYTHON is not set (bpy==5.0.1 venv)"),
]

IMPORT = r"""
import json, sys
import bpy
bpy.ops.wm.read_factory_settings(use_empty=True)
bpy.ops.wm.usd_import(filepath=sys.argv[-1], support_scene_instancing=True)
out = {}
for o in bpy.data.objects:
    props = {k: str(o[k]) for k in o.keys()}
    if o.data is not None and hasattr(o.data, "keys"):
        props.update({k: str(o.data[k]) for k in o.data.keys()})
    out.setdefault(o.name, []).append(props)
print("RESULT" + json.dumps(out))
"""


def test_blender_shows_the_paradata_of_every_part(portunus_temple, tmp_path):
    stage = Usd.Stage.Open(str(portunus_temple.root))
    parts = {}
    for p in stage.Traverse():
        rec = p.GetCustomData().get("paradata")
        path = str(p.GetPath())
        hidden = UsdGeom.Imageable(p) and (
            UsdGeom.Imageable(p).ComputeVisibility() == UsdGeom.Tokens.invisible
        )  # a detail or hypothesis hides what it does not show: Blender imports what is drawn
        if rec and not path.startswith("/Temple/Materials") and not hidden:
            parts[p.GetName()] = dict(rec)
    assert len(parts) > 50
    script = tmp_path / "import.py"
    script.write_text(IMPORT)
    proc = subprocess.run(
        [BPY, str(script), str(portunus_temple.root)], capture_output=True, text=True, timeout=900
    )
    line = next((x for x in proc.stdout.splitlines() if x.startswith("RESULT")), None)
    assert proc.returncode == 0 and line, proc.stderr[-2000:]
    objs = json.loads(line[len("RESULT") :])
    missing = []
    for name, rec in parts.items():
        got = [props for props in objs.get(name, []) if "em:evidence" in props]
        if not got:
            missing.append(name)
            continue
        props = got[0]
        assert props["em:evidence"] == rec["evidence"], name
        assert props["em:certainty"] == rec["certainty"], name
        assert props["em:sources"] == "; ".join(rec["sources"]), name
        assert props["em:unit"] == rec["unit"], name
    assert not missing, f"parts without custom properties in Blender: {missing}"
