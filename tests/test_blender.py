"""Blender (bpy 5.0.1, its own venv) imports the temple's paradata as custom properties.

Needs ``IONIC_USD_BPY_PYTHON`` = the python of a venv with ``bpy==5.0.1`` (CI sets it).
"""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

BPY = os.environ.get("IONIC_USD_BPY_PYTHON")

pytestmark = [
    pytest.mark.slow,
    pytest.mark.skipif(
        not BPY,
        reason="IONIC_USD_BPY_PYTHON is not set: the python of a venv "
        "with bpy==5.0.1 (pip install bpy==5.0.1 under Python 3.11)",
    ),
]

IMPORT = r"""
import json, sys
import bpy
bpy.ops.wm.read_factory_settings(use_empty=True)
bpy.ops.wm.usd_import(filepath=sys.argv[-1], support_scene_instancing=True,
                      import_usd_preview=True)
out = {"objects": {}, "images": [i.name for i in bpy.data.images]}
for o in bpy.data.objects:
    data = o.data if o.data is not None and hasattr(o.data, "keys") else None
    out["objects"][o.name] = {
        "type": o.type,
        "object": {k: str(o[k]) for k in o.keys()},
        "data": {k: str(data[k]) for k in data.keys()} if data is not None else {},
    }
print("RESULT" + json.dumps(out))
"""


def test_blender_shows_hypothesis_paradata(portunus_temple, tmp_path):
    # a view of the temple with two hypotheses selected, as a user would author it
    view = tmp_path / "view.usda"
    view.write_text(f"""#usda 1.0
(
    defaultPrim = "Temple"
    metersPerUnit = 1
    upAxis = "Y"
    subLayers = [@{portunus_temple.root.resolve()}@]
)
over "Temple" (
    variants = {{
        string hyp_frieze = "frieze_plain"
        string hyp_roof_pitch_15 = "alternative"
    }}
)
{{
}}
""")
    script = tmp_path / "import.py"
    script.write_text(IMPORT)
    proc = subprocess.run(
        [BPY, str(script), str(view)], capture_output=True, text=True, timeout=600
    )
    line = next((x for x in proc.stdout.splitlines() if x.startswith("RESULT")), None)
    assert proc.returncode == 0 and line, proc.stderr[-2000:]
    rep = json.loads(line[len("RESULT") :])
    objs = rep["objects"]
    # an Xform carries it on the object, a Mesh on its mesh data
    roof = objs["Roof"]
    assert roof["type"] == "EMPTY"
    assert roof["object"]["ionic_usd:frieze_plain:id"] == "frieze-plain"
    assert roof["object"]["ionic_usd:frieze_plain:certainty"] == "low"
    assert "Vitruvius" in roof["object"]["ionic_usd:frieze_plain:sources"]
    slab = objs["roof_left"]
    assert slab["type"] == "MESH"
    assert slab["data"]["ionic_usd:roof_pitch_15:id"] == "roof-pitch-15"
    assert slab["data"]["ionic_usd:roof_pitch_15:description"].startswith("Roof pitch 15")
    # an untouched part carries none
    assert not any(k.startswith("ionic_usd:") for k in objs["die"]["data"])
    # one copy of every map: no image loaded twice (name.001)
    assert rep["images"] and not [i for i in rep["images"] if re.search(r"\.\d{3}$", i)]


def test_blender_check_tool_passes_on_the_temple(portunus_temple):
    tool = Path(__file__).resolve().parent.parent / "tools" / "blender_check.py"
    proc = subprocess.run(
        [
            sys.executable,
            str(tool),
            str(portunus_temple.root),
            "--instances",
            "18",
            "--prototypes",
            "3",
            "--blender-python",
            BPY,
        ],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert proc.returncode == 0, proc.stdout[-3000:]
    assert "OK:" in proc.stdout
