"""The few objects a user needs, in front of the generators and the USD authoring.

>>> import tempfile, pathlib
>>> import ionic_usd as iu
>>> col = iu.portunus_column(lod="low")
>>> round(col.height, 2), sorted(col.parts())
(8.22, ['Base', 'CapitalBody', 'Shaft'])
>>> col.save(pathlib.Path(tempfile.mkdtemp()) / "column.usda").name
'column.usda'

A temple in five lines (the default scene of ``ionic-usd temple``) is the example of
:class:`Temple`.

Everything here forwards to the modules that do the work (:mod:`ionic_usd.column`,
:mod:`ionic_usd.temple`, :mod:`ionic_usd.usd`); it adds no behaviour of its own.
"""

from __future__ import annotations

import dataclasses
import os
from collections.abc import Collection
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ionic_usd.errors import ParameterError

if TYPE_CHECKING:  # imported lazily at run time: `import ionic_usd` stays light
    from ionic_usd.column.column import Column as _BuiltColumn
    from ionic_usd.column.column import ColumnParams
    from ionic_usd.geometry.mesh import Mesh
    from ionic_usd.pipeline.temple import TempleReport
    from ionic_usd.temple.layout import TempleLayout
    from ionic_usd.temple.mouldings import MouldingParams

__all__ = ["Column", "Temple", "portunus_column", "column"]


@dataclass(frozen=True)
class Column:
    """A built column: its parameters and part meshes, ready to save as USD.

    Attributes
    ----------
    built : ionic_usd.column.column.Column
        The generator's result (part meshes in column coordinates, stacking heights in m).
    """

    built: _BuiltColumn

    @property
    def params(self) -> ColumnParams:
        return self.built.params

    @property
    def height(self) -> float:
        """Height from the base bottom to the abacus top (m)."""
        return self.built.height

    @property
    def n_triangles(self) -> int:
        return self.built.n_triangles

    def parts(self) -> dict[str, Mesh]:
        """Prim name → closed part mesh (``Base``, ``Shaft``, ``CapitalBody``)."""
        return self.built.parts()

    def save(
        self,
        path: str | os.PathLike,
        *,
        force: bool = False,
        parts: Collection[str] | None = None,
    ) -> Path:
        """Write the parts as ``/Column/Geom/<Part>`` into one USD file (atomically).

        The format follows the extension (``.usda`` text, ``.usdc``/``.usd`` binary); an
        existing file needs ``force``. ``parts``: the names of the parts to write, in the
        column's order (default: all). Returns the written path.
        """
        from ionic_usd.usd import check_output_path, write_meshes

        out = check_output_path(path, force=force)
        meshes = self.parts()
        if parts is not None:
            unknown = sorted(set(parts) - set(meshes))
            if unknown or not parts:
                raise ParameterError("parts", sorted(parts), f"some of {', '.join(meshes)}")
            meshes = {k: v for k, v in meshes.items() if k in parts}
        return Path(
            write_meshes(
                out,
                meshes,
                root="Column",
                force=force,
                comment=f"ionic_usd column ({self.params.lod}, base {self.params.base})",
            )
        )


def column(params: ColumnParams | None = None) -> Column:
    """Build a column from :class:`ionic_usd.column.column.ColumnParams` (default: Portunus)."""
    from ionic_usd.column.column import build_column

    return Column(build_column(params))


def portunus_column(**options: Any) -> Column:
    """The Temple of Portunus column (8.22 m, lower diameter 0.95 m, Attic base, 24 flutes).

    ``options`` are those of :func:`ionic_usd.column.column.portunus_column_params`:
    ``lod`` (high, medium, low), ``base`` (a preset name or a base grammar), ``flutes``,
    ``height``, ``lower_diameter``, ``scroll``.
    """
    from ionic_usd.column.column import portunus_column_params

    return column(portunus_column_params(**options))


@dataclass(frozen=True)
class Temple:
    """A temple description (cuboids, colonnade, hypotheses), ready to compose as USD.

    A temple in five lines (run as a slow test: it builds the whole scene):

    >>> import pathlib, tempfile
    >>> import ionic_usd as iu
    >>> temple = iu.Temple.portunus()                  # the Temple of Portunus, Rome
    >>> temple = temple.with_hypotheses("flutes-20")   # optional: a hypothesis in the layout
    >>> report = temple.save(pathlib.Path(tempfile.mkdtemp()) / "PortunusTemple")
    >>> report.instances, report.prototypes, report.root.name
    (18, 3, 'Temple.usda')
    """

    layout: TempleLayout
    column: ColumnParams | None = None
    mouldings: MouldingParams | None = None

    @classmethod
    def portunus(cls) -> Temple:
        """The Temple of Portunus (Forum Boarium, Rome), every dimension cited in
        ``ionic_usd/data/portunus.toml``."""
        from ionic_usd.temple.layout import portunus_layout

        return cls(portunus_layout())

    @classmethod
    def from_toml(cls, path: str | os.PathLike) -> Temple:
        """A temple described in TOML with the schema of ``ionic_usd/data/portunus.toml``.

        The file may add ``[column]``, ``[shaft]``, ``[capital]`` and ``[volute]`` tables
        for its column (over the Portunus column scaled to the description's columns) and a
        ``[mouldings]`` table: what ``ionic-usd temple --config`` reads.
        """
        from ionic_usd.column.column import column_params_from_mapping
        from ionic_usd.params import load_toml
        from ionic_usd.temple.layout import layout_from_mapping
        from ionic_usd.temple.mouldings import mouldings_from_tables
        from ionic_usd.temple.tables import resolve_extends

        data = load_toml(path)
        if "extends" in data:  # what it inherits (the mouldings and column tables too)
            data = resolve_extends(data, context=str(path))
        mouldings = mouldings_from_tables(data, context=str(path))
        tables = {k: data.pop(k) for k in ("column", "shaft", "capital", "volute") if k in data}
        temple = cls(layout_from_mapping(data, context=str(path)), None, mouldings)
        if not tables:
            return temple
        column = column_params_from_mapping(tables, context=str(path), base=temple.column_params)
        return dataclasses.replace(temple, column=column)

    @property
    def column_params(self) -> ColumnParams:
        """The column the temple instances: :attr:`column`, else the Portunus column at the
        description's column height and lower diameter."""
        if self.column is not None:
            return self.column
        from ionic_usd.blueprint.temple import temple_column_params

        return temple_column_params(self.layout)

    def with_hypotheses(self, *ids: str) -> Temple:
        """The Portunus layout with the named hypotheses applied in the geometry itself."""
        from ionic_usd.temple.layout import portunus_layout

        return dataclasses.replace(self, layout=portunus_layout(apply=ids))

    def save(
        self, folder: str | os.PathLike, *, force: bool = False, **options: Any
    ) -> TempleReport:
        """Compose the temple folder (``Temple.usda`` + layers + the column asset).

        ``options`` go to :func:`ionic_usd.pipeline.temple.compose_temple` (``texture_size``,
        ``seed``, ``detail``, ``rebuild``). A folder that already holds this build's intact
        output is left as it is (``report.current``). Returns its
        :class:`~ionic_usd.pipeline.temple.TempleReport`.
        """
        from ionic_usd.pipeline.temple import compose_temple

        return compose_temple(
            folder, self.layout, self.column, force=force, mouldings=self.mouldings, **options
        )

    def current(self, folder: str | os.PathLike, **options: Any) -> TempleReport | None:
        """The report of ``folder`` if it already holds this temple's build (same description,
        options, code and libraries; every generated file intact), else None. Loads no USD."""
        from ionic_usd.pipeline.temple import current_temple

        return current_temple(folder, self.layout, self.column, mouldings=self.mouldings, **options)
