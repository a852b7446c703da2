"""Stage creation, atomic saving and validation — every stage ionic_usd writes goes through here."""

from __future__ import annotations

import os
from collections.abc import Iterable, Mapping
from pathlib import Path

from pxr import Kind, Sdf, Usd, UsdGeom, Vt

from ionic_usd.errors import ParameterError, UsdAuthoringError

__all__ = [
    "USD_EXTENSIONS",
    "create_stage",
    "new_layer",
    "save_layer",
    "save_stage",
    "check_output_path",
    "validate_stage",
    "ensure_typed_ancestors",
    "vt_dictionary",
]

USD_EXTENSIONS = (".usda", ".usdc", ".usd")
_KINDS = ("component", "assembly", "group", "subcomponent", "model")


def check_output_path(path: str | os.PathLike, *, force: bool = False) -> Path:
    """Validate an output path: a USD extension, and no existing file unless ``force``."""
    from ionic_usd.io import check_output_file

    return check_output_file(path, force=force, suffixes=USD_EXTENSIONS)


def new_layer(
    default_prim: str,
    *,
    kind: str | None = "component",
    prim_type: str = "Xform",
    up_axis: str = "Y",
    meters_per_unit: float = 1.0,
    comment: str = "",
) -> Sdf.Layer:
    """An anonymous layer with the stage metadata every ionic_usd layer carries.

    Sets ``defaultPrim``, ``upAxis``, ``metersPerUnit`` and defines the default prim with its
    type and ``kind`` — what Pixar's StageMetadataChecker and DCC importers expect.
    """
    if kind is not None and kind not in _KINDS:
        raise ParameterError("kind", kind, f"one of {', '.join(_KINDS)}")
    if up_axis not in ("Y", "Z"):
        raise ParameterError("up_axis", up_axis, "'Y' or 'Z'")
    layer = Sdf.Layer.CreateAnonymous(".usda")
    with Sdf.ChangeBlock():
        spec = Sdf.CreatePrimInLayer(layer, Sdf.Path.absoluteRootPath.AppendChild(default_prim))
        spec.specifier = Sdf.SpecifierDef
        spec.typeName = prim_type
        if kind is not None:
            spec.kind = kind
        layer.defaultPrim = default_prim
        root = layer.pseudoRoot
        root.SetInfo("upAxis", up_axis)
        root.SetInfo("metersPerUnit", float(meters_per_unit))
        if comment:
            layer.comment = comment
    return layer


def create_stage(default_prim: str, **metadata) -> Usd.Stage:
    """An in-memory stage whose root layer comes from :func:`new_layer` (same keywords)."""
    return Usd.Stage.Open(new_layer(default_prim, **metadata))


def save_layer(layer: Sdf.Layer, path: str | os.PathLike, *, force: bool = False) -> Path:
    """Export a layer atomically: write a temporary file beside ``path``, then rename.

    The file format follows the extension (``.usda`` text, ``.usdc``/``.usd`` crate).
    """
    from ionic_usd.io import atomic_path

    p = check_output_path(path, force=force)
    p.parent.mkdir(parents=True, exist_ok=True)

    def readable(tmp: Path) -> None:  # a full disk can leave a truncated layer behind
        try:
            ok = Sdf.Layer.OpenAsAnonymous(str(tmp)) is not None
        except Exception:  # pxr.Tf.ErrorException: "Sdf crate file corrupt, possibly truncated"
            ok = False
        if not ok:
            cause = write_failure_cause(p, tmp) or "the written layer does not read back"
            raise UsdAuthoringError(f"{cause}: could not write {p}")

    with atomic_path(p, verify=readable) as tmp:
        try:
            ok = layer.Export(str(tmp))
        except Exception as exc:  # pxr.Tf.ErrorException: OS errors surface as this
            cause = write_failure_cause(p, tmp)
            if cause is None:
                why = _first_line(exc).replace(str(tmp), p.name)
                raise UsdAuthoringError(f"could not write {p}: {why}") from None
            raise UsdAuthoringError(f"{cause}: could not write {p}") from None
        if not ok:
            cause = write_failure_cause(p, tmp)
            raise UsdAuthoringError(
                f"{cause or 'OpenUSD could not export the layer'}: could not write {p}"
            )
    # a later Sdf.Layer.FindOrOpen of this path must see the new content, not a cached one
    cached = Sdf.Layer.Find(str(p))
    if cached is not None:
        cached.Reload(force=True)
    return p


def _first_line(exc: BaseException) -> str:
    """The message of a ``Tf.ErrorException`` without its C++ location."""
    lines = [ln.strip() for ln in str(exc).splitlines() if ln.strip()]
    text = lines[-1] if lines else type(exc).__name__
    if text.startswith("Error in ") and " : " in text:
        text = text.rsplit(" : ", 1)[1].strip("'\" ")
    return text


def write_failure_cause(p: Path, tmp: Path | None = None) -> str | None:
    """Why writing ``p`` failed, when the OS can tell (OpenUSD's own text only says "Could not
    close" or "crate file corrupt"): a full disk, or the process' file-size limit."""
    import resource

    soft, _hard = resource.getrlimit(resource.RLIMIT_FSIZE)
    if soft != resource.RLIM_INFINITY:
        try:
            size = tmp.stat().st_size if tmp is not None else 0
        except OSError:
            size = 0
        if size >= soft - (64 << 10):
            return (
                f"File too large (this process may write files of at most {soft:,} bytes: "
                "ulimit -f)"
            )
    try:
        st = os.statvfs(p.parent)
    except OSError:
        return None
    if st.f_bavail * st.f_frsize < (1 << 20):
        return "No space left on device (free some space or write elsewhere)"
    return None


def save_stage(stage: Usd.Stage, path: str | os.PathLike, *, force: bool = False) -> Path:
    """Flatten nothing: export the stage's root layer atomically (see :func:`save_layer`)."""
    return save_layer(stage.GetRootLayer(), path, force=force)


def ensure_typed_ancestors(layer: Sdf.Layer, path: Sdf.Path, prim_type: str = "Xform") -> None:
    """Give every untyped ancestor spec of ``path`` a type (Blender drops untyped parents)."""
    for anc in path.GetParentPath().GetPrefixes():
        spec = layer.GetPrimAtPath(anc)
        if spec is None:
            spec = Sdf.CreatePrimInLayer(layer, anc)
            spec.specifier = Sdf.SpecifierDef
        if not spec.typeName and spec.specifier == Sdf.SpecifierDef:
            spec.typeName = prim_type


def validate_stage(
    stage: Usd.Stage | str | os.PathLike, *, include: Iterable[str] | None = None
) -> list[str]:
    """Run OpenUSD's registered validators (``pxr.UsdValidation``); return the error messages.

    Warnings are not returned. ``include`` restricts to validators by name.
    """
    from pxr import UsdValidation  # noqa: PLC0415 - heavy plugin load only when validating

    if not isinstance(stage, Usd.Stage):
        opened = Usd.Stage.Open(str(stage))
        if opened is None:
            raise UsdAuthoringError(f"cannot open {stage}")
        stage = opened
    reg = UsdValidation.ValidationRegistry()
    if include is None:
        validators = reg.GetOrLoadAllValidators()
    else:
        validators = reg.GetOrLoadValidatorsByName(list(include))
    ctx = UsdValidation.ValidationContext(validators)
    errors = ctx.Validate(stage)
    return [
        e.GetErrorAsString()
        for e in errors
        if not e.HasNoError() and e.GetType() == UsdValidation.ValidationErrorType.Error
    ]


def model_kind(prim: Usd.Prim) -> str:
    """The kind of a prim ('' when none)."""
    return str(Usd.ModelAPI(prim).GetKind() or "")


_ = (Kind, UsdGeom)


def vt_dictionary(d: Mapping) -> dict:
    """A JSON-like mapping as USD customData: nested mappings as dictionaries, lists of
    strings or numbers as ``string[]`` / ``double[]``; lists of records and values of other
    types (``None``) are left out."""
    out: dict = {}
    for k, v in d.items():
        if isinstance(v, Mapping):
            out[str(k)] = vt_dictionary(v)
        elif isinstance(v, (list, tuple)):
            if any(isinstance(x, Mapping) for x in v):
                continue  # per-lot records stay in the JSON summary
            if all(isinstance(x, str) for x in v):
                out[str(k)] = Vt.StringArray([str(x) for x in v])
            else:
                out[str(k)] = Vt.DoubleArray([float(x) for x in v])
        elif isinstance(v, bool) or isinstance(v, (int, float, str)):
            out[str(k)] = v
    return out
