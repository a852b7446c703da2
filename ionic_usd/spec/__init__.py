"""What to write: the product's vocabulary and descriptions, with no ``pxr``.

Generation, the pipeline and :mod:`ionic_usd.usd` share these; ``usd/`` keeps the writers
(and the one reader) and turns a description into layers. Nothing under ``spec/`` imports
``pxr`` (``tests/test_layering.py`` imports it in a fresh interpreter and checks), so a mesh
worker or the up-to-date check that needs a name or an option loads no USD.

- :mod:`ionic_usd.spec.layers`: the file and prim names of the folders the package writes
  (standard library only);
- :mod:`ionic_usd.spec.materials`: a material's texture paths, the stone maps' tile size;
- :mod:`ionic_usd.spec.asset`: a component asset's description (meshes, instancers, variant
  sets, materials), which :func:`ionic_usd.usd.asset.write_asset` authors;
- :mod:`ionic_usd.spec.column_asset`: the column asset's variant vocabulary, its build options
  and its description (:func:`~ionic_usd.spec.column_asset.column_asset_spec`).

The levels of detail are :mod:`ionic_usd.lod`.
"""
