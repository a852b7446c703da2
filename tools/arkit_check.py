"""Check usdz packages against Apple's ARKit profile (usd-core's ComplianceChecker, arkit=True).

``UsdUtils.ComplianceChecker`` left usd-core after 24.x; it runs in a venv of its own with
``usd-core==24.11`` (tools/check_arkit.sh makes one). Run it with that venv's Python::

    /path/to/venv/bin/python tools/arkit_check.py temple.usdz --shader-defs shaderDefs.usda

Every rule of the ARKit profile runs (root layer, package encapsulation, prim types, shader
types, materials, texture formats, …); the exit status is 1 when any check fails or errors.

One gap of the 24.x wheels is bridged, not hidden: they ship no ``usdShaders`` plugin, so Sdr
knows no ``UsdPreviewSurface``/``UsdUVTexture``/``UsdPrimvarReader_float2``/
``UsdTransform2d`` node and the ShaderPropertyTypeConformanceChecker fails every shader with
"invalid shader node". ``--shader-defs`` names USD's own ``shaderDefs.usda`` (the project's
usd-core has it: pxr/pluginfo/usdShaders/resources/shaders/); when Sdr does not know a shader
id, the checker gets a node whose input names and Sdf types are read from that file's
definition, so every input of every shader is still compared with the specification.
"""

from __future__ import annotations

import argparse
import sys


def _defs_registry(defs_path: str | None):
    """A stand-in for ``Sdr.Registry()``: the real one, and for shader ids it lacks a node
    built from the ``shaderDefs.usda`` definitions."""
    from pxr import Sdr, Tf, Usd, UsdShade

    try:
        real = Sdr.Registry()
    except Tf.ErrorException:  # 24.x wheels: usdHydra's discovery misses its shaderDefs.usda
        real = Sdr.Registry()  # made all the same, without usdHydra's (deprecated) nodes
    defs: dict[str, dict] = {}
    if defs_path:
        stage = Usd.Stage.Open(defs_path)
        for prim in stage.Traverse():
            sh = UsdShade.Shader(prim)
            if sh:
                defs[prim.GetName()] = {i.GetBaseName(): i.GetTypeName() for i in sh.GetInputs()}

    class _Type:
        def __init__(self, t):
            self._t = t

        def GetSdfType(self):
            return self._t

    class _Prop:
        def __init__(self, name, t):
            self._name, self._t = name, t

        def GetName(self):
            return self._name

        def GetTypeAsSdfType(self):
            return _Type(self._t)

    class _Node:
        def __init__(self, inputs):
            self._inputs = inputs

        def __bool__(self):
            return True

        def GetInputNames(self):
            return list(self._inputs)

        def GetInput(self, name):
            return _Prop(name, self._inputs[name])

    class _Registry:
        def __getattr__(self, name):
            return getattr(real, name)

        def GetShaderNodeByIdentifier(self, ident, *args):
            try:
                node = real.GetShaderNodeByIdentifier(ident, *args)
            except Tf.ErrorException:
                node = None
            if not node and ident in defs:
                return _Node(defs[ident])
            return node

    registry = _Registry()
    return lambda: registry


def check(path: str, defs_path: str | None) -> tuple[list[str], list[str], list[str]]:
    """(errors, failed checks, warnings) of the ARKit profile for one file."""
    from pxr import Sdr, UsdGeom, UsdShade, UsdUtils  # noqa: F401  (load order for Sdr)

    Sdr.Registry = _defs_registry(defs_path)  # the checker calls pxr.Sdr.Registry() itself
    c = UsdUtils.ComplianceChecker(
        arkit=True, skipARKitRootLayerCheck=False, rootPackageOnly=False, skipVariants=False
    )
    c.CheckCompliance(path)
    return list(c.GetErrors()), list(c.GetFailedChecks()), list(c.GetWarnings())


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("usdz", nargs="+")
    ap.add_argument("--shader-defs", help="USD's usdShaders shaderDefs.usda")
    args = ap.parse_args(argv)
    from pxr import Usd, UsdUtils

    bad = 0
    for path in args.usdz:
        errors, failed, warnings = check(path, args.shader_defs)
        for kind, items in (("ERROR", errors), ("FAILED", failed), ("warning", warnings)):
            for m in items:
                print(f"  {kind}: {m}")
        rules = len(UsdUtils.ComplianceChecker.GetRules(arkit=True))
        print(
            f"ARKit profile (usd-core {'.'.join(map(str, Usd.GetVersion()))}, {rules} rules): "
            f"{path}: {len(errors)} errors, {len(failed)} failed checks, "
            f"{len(warnings)} warnings"
        )
        bad += bool(errors or failed)
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
