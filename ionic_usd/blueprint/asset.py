"""A component asset's description as values (no ``pxr``): what
:func:`ionic_usd.usd.asset.write_asset` authors (the layout of the folder is described there).

Each mesh carries tags — the variant it belongs to in each variant set that concerns it (a
shaft is tagged only with ``lod``, ``flutes`` and ``form``); :class:`AssetSpec` checks that
every tag names a declared set and variant, every default a variant, every material a
declared one.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from ionic_usd.blueprint.materials import MaterialTextures
from ionic_usd.errors import ParameterError
from ionic_usd.geometry.mesh import Mesh

if TYPE_CHECKING:  # the ornament module is imported only when an asset has instancers
    from ionic_usd.column.ornament import Instances

__all__ = ["AssetInstancer", "AssetMesh", "AssetSpec"]


@dataclass(frozen=True)
class AssetMesh:
    """One mesh of the asset: ``/<Name>/Geom/<part>/<name>`` with its variant tags."""

    part: str
    name: str
    mesh: Mesh
    tags: Mapping[str, str]


@dataclass(frozen=True)
class AssetInstancer:
    """A PointInstancer ``/<Name>/Geom/<part>/<name>`` of ornament (see
    :mod:`ionic_usd.usd.instancer`), switched by its variant tags like a mesh."""

    part: str
    name: str
    instances: Instances
    tags: Mapping[str, str]


@dataclass(frozen=True)
class AssetSpec:
    """Everything an asset holds; paths of textures are relative to ``Payload/``.

    ``variant_sets`` maps each set to its variants in display order; ``defaults`` gives each
    set's selection. ``finishes`` maps a variant of the ``finish`` set (if present) to a
    material name; ``materials`` maps material names to their textures.
    """

    name: str
    version: str
    meshes: tuple[AssetMesh, ...]
    variant_sets: Mapping[str, tuple[str, ...]]
    defaults: Mapping[str, str]
    materials: Mapping[str, MaterialTextures]
    default_material: str
    finishes: Mapping[str, str] = field(default_factory=dict)
    st_scale: float | None = None
    custom_data: Mapping[str, object] = field(default_factory=dict)
    documentation: str = ""
    proxy_lod: str | None = None  # this lod's meshes, always loaded, as the proxy purpose
    instancers: tuple[AssetInstancer, ...] = ()

    def __post_init__(self) -> None:
        for vset, variants in self.variant_sets.items():
            sel = self.defaults.get(vset)
            if sel not in variants:
                raise ParameterError(f"defaults[{vset!r}]", sel, f"one of {', '.join(variants)}")
        for m in self.tagged():
            for vset, v in m.tags.items():
                if vset not in self.variant_sets or v not in self.variant_sets[vset]:
                    raise ParameterError(
                        f"tags of {m.part}/{m.name}",
                        dict(m.tags),
                        "variant sets and variants declared by the asset",
                    )
        if self.proxy_lod is not None and self.proxy_lod not in self.variant_sets.get("lod", ()):
            raise ParameterError("proxy_lod", self.proxy_lod, "a variant of the lod set")
        if self.default_material not in self.materials:
            raise ParameterError(
                "default_material", self.default_material, f"one of {', '.join(self.materials)}"
            )
        for fin, mat in self.finishes.items():
            if mat not in self.materials:
                raise ParameterError(
                    f"finishes[{fin!r}]", mat, f"one of {', '.join(self.materials)}"
                )

    def tagged(self) -> tuple[AssetMesh | AssetInstancer, ...]:
        """Every mesh and instancer of the asset (what variant tags switch)."""
        return (*self.meshes, *self.instancers)
